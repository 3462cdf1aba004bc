//! VTK XML PolyData (`.vtp`) reader. Supports every encoding VTK writes: `ascii`, inline
//! `binary` (base64) and `appended` (raw or base64), each with a `UInt32` or `UInt64` header
//! and with or without `vtkZLibDataCompressor` block compression; any byte order; several
//! pieces (merged). Geometry: `Points` (Float32/Float64), `Polys` (fan-triangulated) and
//! `Strips` (split into triangles); `Verts`/`Lines` only count towards cell numbering.
//! Labels: `PointData`/`CellData` arrays named like `label` (any numeric type).
//!
//! The XML part is parsed by `quick-xml`; the appended block (raw bytes are not XML) is cut
//! off first and addressed by the arrays' `offset` attributes.

use super::{FaceBuilder, check_finite, check_vertex_count, label_from_f64, label_rank};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result};
use base64::Engine;
use glam::DVec3;
use quick_xml::events::{BytesStart, Event};
use std::io::Read;

pub use super::vtp_write::{VtpEncoding, write_vtp};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Section {
    None,
    PointData,
    CellData,
    Points,
    Verts,
    Lines,
    Polys,
    Strips,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ArrayFormat {
    Ascii,
    Binary,
    Appended,
}

#[derive(Debug)]
struct ArrayDesc {
    section: Section,
    ty: String,
    name: String,
    components: usize,
    format: ArrayFormat,
    offset: usize,
    text: Vec<u8>,
}

#[derive(Debug, Default)]
struct Piece {
    points: usize,
    verts: usize,
    lines: usize,
    polys: usize,
    strips: usize,
    arrays: Vec<ArrayDesc>,
}

struct Ctx<'a> {
    file: &'a str,
    big_endian: bool,
    header64: bool,
    compressed: bool,
    appended_base64: bool,
    /// The appended block after its leading `_`.
    appended: &'a [u8],
    /// Sorted distinct offsets of all appended arrays (to find where a base64 array ends).
    offsets: Vec<usize>,
}

/// Reads a VTK XML PolyData file held in memory; `file` names it in error messages.
pub fn read_vtp_bytes(file: &str, bytes: &[u8]) -> Result<LabeledMesh> {
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let app_pos = find(bytes, b"<AppendedData");
    let xml = &bytes[..app_pos.unwrap_or(bytes.len())];
    let mut rd = quick_xml::Reader::from_reader(xml);
    rd.config_mut().check_end_names = false;
    let mut ctx = Ctx {
        file,
        big_endian: false,
        header64: false,
        compressed: false,
        appended_base64: false,
        appended: &[],
        offsets: Vec::new(),
    };
    let mut seen_root = false;
    let mut pieces: Vec<Piece> = Vec::new();
    let mut section = Section::None;
    let mut current: Option<ArrayDesc> = None;
    loop {
        let pos = rd.buffer_position();
        let ev = rd
            .read_event()
            .map_err(|e| err(format!("malformed XML near byte {pos}: {e}")))?;
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let empty = matches!(ev, Event::Empty(_));
                let name = e.name().as_ref().to_string();
                match name.as_str() {
                    "VTKFile" => {
                        seen_root = true;
                        let ty = attr(e, "type")?.unwrap_or_default();
                        if ty != "PolyData" {
                            return Err(err(format!(
                                "VTKFile type is {ty:?}; only PolyData is supported"
                            )));
                        }
                        ctx.big_endian = attr(e, "byte_order")?.as_deref() == Some("BigEndian");
                        ctx.header64 = match attr(e, "header_type")?.as_deref() {
                            None | Some("UInt32") => false,
                            Some("UInt64") => true,
                            Some(h) => {
                                return Err(err(format!(
                                    "header_type {h:?} (expected UInt32 or UInt64)"
                                )));
                            }
                        };
                        ctx.compressed = match attr(e, "compressor")?.as_deref() {
                            None | Some("") => false,
                            Some("vtkZLibDataCompressor") => true,
                            Some(c) => {
                                return Err(err(format!(
                                    "compressor {c:?} is not supported (only vtkZLibDataCompressor)"
                                )));
                            }
                        };
                    }
                    "Piece" => {
                        let n = |k: &str| -> Result<usize> {
                            match attr(e, k)? {
                                None => Ok(0),
                                Some(v) => v.trim().parse().map_err(|_| {
                                    err(format!("Piece attribute {k}={v:?} is not a count"))
                                }),
                            }
                        };
                        pieces.push(Piece {
                            points: n("NumberOfPoints")?,
                            verts: n("NumberOfVerts")?,
                            lines: n("NumberOfLines")?,
                            polys: n("NumberOfPolys")?,
                            strips: n("NumberOfStrips")?,
                            arrays: Vec::new(),
                        });
                    }
                    "PointData" | "CellData" | "Points" | "Verts" | "Lines" | "Polys"
                    | "Strips"
                        if !empty =>
                    {
                        section = match name.as_str() {
                            "PointData" => Section::PointData,
                            "CellData" => Section::CellData,
                            "Points" => Section::Points,
                            "Verts" => Section::Verts,
                            "Lines" => Section::Lines,
                            "Polys" => Section::Polys,
                            _ => Section::Strips,
                        };
                    }
                    "DataArray" if section != Section::None && !pieces.is_empty() => {
                        let d = array_desc(file, e, section)?;
                        if empty {
                            if let Some(p) = pieces.last_mut() {
                                p.arrays.push(d);
                            }
                        } else {
                            current = Some(d);
                        }
                    }
                    _ => {}
                }
            }
            Event::Text(t) => {
                if let Some(d) = current.as_mut() {
                    d.text.extend_from_slice(t.into_inner().as_bytes());
                }
            }
            Event::End(e) => match e.name().as_ref() {
                "DataArray" => {
                    if let (Some(d), Some(p)) = (current.take(), pieces.last_mut()) {
                        p.arrays.push(d);
                    }
                }
                "PointData" | "CellData" | "Points" | "Verts" | "Lines" | "Polys" | "Strips" => {
                    section = Section::None
                }
                _ => {}
            },
            Event::Eof => break,
            _ => {}
        }
    }
    if !seen_root {
        return Err(err("no <VTKFile> element: not a VTK XML file".into()));
    }
    if pieces.is_empty() {
        return Err(err("no <Piece> in <PolyData>".into()));
    }
    if let Some(p) = app_pos {
        let tail = &bytes[p..];
        let gt = find(tail, b">").ok_or_else(|| err("unterminated <AppendedData> tag".into()))?;
        let tag = String::from_utf8_lossy(&tail[..gt]);
        ctx.appended_base64 = if tag.contains("\"base64\"") {
            true
        } else if tag.contains("\"raw\"") {
            false
        } else {
            return Err(err(format!(
                "<AppendedData> encoding missing or unknown in `{tag}>` (expected raw or base64)"
            )));
        };
        let us = find(&tail[gt..], b"_")
            .ok_or_else(|| err("appended data lacks its leading `_`".into()))?;
        ctx.appended = &tail[gt + us + 1..];
        if ctx.appended_base64 {
            let end = find(ctx.appended, b"<").unwrap_or(ctx.appended.len());
            ctx.appended = &ctx.appended[..end];
        }
        let mut offs: Vec<usize> = pieces
            .iter()
            .flat_map(|p| &p.arrays)
            .filter(|a| a.format == ArrayFormat::Appended)
            .map(|a| a.offset)
            .collect();
        offs.sort_unstable();
        offs.dedup();
        ctx.offsets = offs;
    }
    assemble(&ctx, &pieces)
}

fn assemble(ctx: &Ctx, pieces: &[Piece]) -> Result<LabeledMesh> {
    let file = ctx.file;
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let mut positions: Vec<DVec3> = Vec::new();
    let mut triangles = Vec::new();
    let (mut vlabels, mut flabels): (Option<Vec<i32>>, Option<Vec<i32>>) = (None, None);
    let all_have = |s: Section| {
        pieces
            .iter()
            .all(|p| pick_label(p, s).is_some() || count_of(p, s) == 0)
    };
    let use_v = pieces
        .iter()
        .any(|p| pick_label(p, Section::PointData).is_some())
        && all_have(Section::PointData);
    let use_f = pieces
        .iter()
        .any(|p| pick_label(p, Section::CellData).is_some())
        && all_have(Section::CellData);
    for (pi, p) in pieces.iter().enumerate() {
        let base = positions.len();
        let pts = match find_array(p, Section::Points, None) {
            Some(a) => {
                if a.components != 3 {
                    return Err(err(format!(
                        "piece {pi}: Points has {} components (expected 3)",
                        a.components
                    )));
                }
                decode(ctx, a, p.points * 3)?
            }
            None if p.points == 0 => Vec::new(),
            None => return Err(err(format!("piece {pi}: no Points array"))),
        };
        positions.extend(pts.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])));
        check_vertex_count(file, positions.len())?;
        let mut fb = FaceBuilder::new(file, p.points);
        for (sec, n) in [(Section::Polys, p.polys), (Section::Strips, p.strips)] {
            let (conn, offs) = cells(ctx, p, sec, n, pi)?;
            let mut start = 0usize;
            for &end in &offs {
                let idx = &conn[start..end];
                if sec == Section::Polys {
                    fb.polygon(idx)?;
                } else {
                    fb.strip(idx)?;
                }
                start = end;
            }
        }
        let first_poly_cell = p.verts + p.lines;
        let n_cells = p.verts + p.lines + p.polys + p.strips;
        triangles.extend(fb.triangles.iter().map(|t| t.map(|v| v + base as u32)));
        if use_v {
            let a = pick_label(p, Section::PointData);
            let vals = match a {
                Some(a) => labels_of(ctx, a, p.points, "vertex")?,
                None => Vec::new(),
            };
            vlabels.get_or_insert_with(Vec::new).extend(vals);
        }
        if use_f {
            let vals = match pick_label(p, Section::CellData) {
                Some(a) => labels_of(ctx, a, n_cells, "cell")?,
                None => Vec::new(),
            };
            let out = flabels.get_or_insert_with(Vec::new);
            // Polys are cells verts+lines.., strips follow the polys: both are consecutive.
            out.extend(
                fb.source_poly
                    .iter()
                    .map(|&c| vals[first_poly_cell + c as usize]),
            );
        }
        debug_assert_eq!(fb.poly_count(), p.polys + p.strips);
    }
    check_finite(file, &positions)?;
    Ok(LabeledMesh {
        mesh: TriMesh::new(positions, triangles),
        vertex_labels: vlabels,
        face_labels: flabels,
    })
}

fn count_of(p: &Piece, s: Section) -> usize {
    match s {
        Section::PointData => p.points,
        _ => p.verts + p.lines + p.polys + p.strips,
    }
}

fn labels_of(ctx: &Ctx, a: &ArrayDesc, n: usize, what: &str) -> Result<Vec<i32>> {
    if a.components != 1 {
        return Err(Error::Io(format!(
            "{}: label array {:?} has {} components (expected 1)",
            ctx.file, a.name, a.components
        )));
    }
    decode(ctx, a, n)?
        .into_iter()
        .enumerate()
        .map(|(i, v)| label_from_f64(v, ctx.file, what, i))
        .collect()
}

/// Connectivity and end offsets of one cell section, checked for consistency.
fn cells(
    ctx: &Ctx,
    p: &Piece,
    sec: Section,
    n: usize,
    pi: usize,
) -> Result<(Vec<i64>, Vec<usize>)> {
    let file = ctx.file;
    if n == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    let (Some(oa), Some(ca)) = (
        find_array(p, sec, Some("offsets")),
        find_array(p, sec, Some("connectivity")),
    ) else {
        return Err(Error::Io(format!(
            "{file}: piece {pi}: {sec:?} needs `connectivity` and `offsets` arrays"
        )));
    };
    let offs = decode(ctx, oa, n)?;
    let mut ends = Vec::with_capacity(n);
    let mut prev = 0usize;
    for (i, &o) in offs.iter().enumerate() {
        if o.fract() != 0.0 || o < prev as f64 || o > 1e15 {
            return Err(Error::Io(format!(
                "{file}: piece {pi}: {sec:?} offsets[{i}] = {o} (expected a non-decreasing end index)"
            )));
        }
        prev = o as usize;
        ends.push(prev);
    }
    let conn = decode(ctx, ca, prev)?
        .into_iter()
        .map(|v| {
            if v.fract() == 0.0 && v.abs() < 9e15 {
                v as i64
            } else {
                -1
            }
        })
        .collect();
    Ok((conn, ends))
}

fn find_array<'p>(p: &'p Piece, s: Section, name: Option<&str>) -> Option<&'p ArrayDesc> {
    p.arrays
        .iter()
        .find(|a| a.section == s && name.is_none_or(|n| a.name == n))
}

fn pick_label(p: &Piece, s: Section) -> Option<&ArrayDesc> {
    p.arrays
        .iter()
        .filter(|a| a.section == s)
        .filter_map(|a| label_rank(&a.name).map(|r| (r, a)))
        .min_by_key(|(r, _)| *r)
        .map(|(_, a)| a)
}

fn attr(e: &BytesStart, key: &str) -> Result<Option<String>> {
    for a in e.attributes().with_checks(false) {
        let a = a.map_err(|x| Error::Io(format!("malformed XML attribute: {x}")))?;
        if a.key.as_ref() == key {
            return Ok(Some(a.value.into_owned()));
        }
    }
    Ok(None)
}

fn array_desc(file: &str, e: &BytesStart, section: Section) -> Result<ArrayDesc> {
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let ty = attr(e, "type")?.ok_or_else(|| err("DataArray without a type".into()))?;
    let name = attr(e, "Name")?.unwrap_or_default();
    let components = match attr(e, "NumberOfComponents")? {
        None => 1,
        Some(c) => c
            .trim()
            .parse()
            .map_err(|_| err(format!("DataArray {name:?}: NumberOfComponents {c:?}")))?,
    };
    let format = match attr(e, "format")?.as_deref() {
        Some("ascii") => ArrayFormat::Ascii,
        Some("binary") => ArrayFormat::Binary,
        Some("appended") => ArrayFormat::Appended,
        f => {
            return Err(err(format!(
                "DataArray {name:?}: format {f:?} (expected ascii, binary or appended)"
            )));
        }
    };
    let offset = match (format, attr(e, "offset")?) {
        (ArrayFormat::Appended, Some(o)) => o
            .trim()
            .parse()
            .map_err(|_| err(format!("DataArray {name:?}: offset {o:?} is not a number")))?,
        (ArrayFormat::Appended, None) => {
            return Err(err(format!("appended DataArray {name:?} has no offset")));
        }
        _ => 0,
    };
    Ok(ArrayDesc {
        section,
        ty,
        name,
        components,
        format,
        offset,
        text: Vec::new(),
    })
}

fn type_size(ty: &str) -> Option<usize> {
    Some(match ty {
        "Int8" | "UInt8" | "Char" => 1,
        "Int16" | "UInt16" => 2,
        "Int32" | "UInt32" | "Float32" => 4,
        "Int64" | "UInt64" | "Float64" => 8,
        _ => return None,
    })
}

/// Decodes array `a`, which must hold exactly `values` numbers (tuples × components).
fn decode(ctx: &Ctx, a: &ArrayDesc, values: usize) -> Result<Vec<f64>> {
    let file = ctx.file;
    let err = |m: String| Error::Io(format!("{file}: DataArray {:?}: {m}", a.name));
    let size = type_size(&a.ty).ok_or_else(|| err(format!("unsupported type {:?}", a.ty)))?;
    let raw = match a.format {
        ArrayFormat::Ascii => {
            let text = String::from_utf8_lossy(&a.text);
            let v: Vec<f64> = text
                .split_ascii_whitespace()
                .enumerate()
                .map(|(i, t)| {
                    t.parse::<f64>()
                        .map_err(|_| err(format!("value {i} = {t:?} is not a number")))
                })
                .collect::<Result<_>>()?;
            if v.len() != values {
                return Err(err(format!("{} ascii values, expected {values}", v.len())));
            }
            return Ok(v);
        }
        ArrayFormat::Binary => {
            let bytes = b64(&a.text).map_err(&err)?;
            block(ctx, &bytes, values * size).map_err(&err)?
        }
        ArrayFormat::Appended => {
            if a.offset > ctx.appended.len() {
                return Err(err(format!(
                    "offset {} lies beyond the appended data ({} bytes)",
                    a.offset,
                    ctx.appended.len()
                )));
            }
            if ctx.appended_base64 {
                let end = ctx
                    .offsets
                    .iter()
                    .find(|&&o| o > a.offset)
                    .copied()
                    .unwrap_or(ctx.appended.len())
                    .min(ctx.appended.len());
                let bytes = b64(&ctx.appended[a.offset..end]).map_err(&err)?;
                block(ctx, &bytes, values * size).map_err(&err)?
            } else {
                block(ctx, &ctx.appended[a.offset..], values * size)
                    .map_err(|m| err(format!("at appended offset {}: {m}", a.offset)))?
            }
        }
    };
    Ok(to_f64(&raw, &a.ty, size, ctx.big_endian))
}

/// Reads one binary block (header + data, optionally zlib-compressed in blocks) that must
/// decode to exactly `want` bytes; trailing bytes after it are ignored.
fn block(ctx: &Ctx, b: &[u8], want: usize) -> std::result::Result<Vec<u8>, String> {
    let hs = if ctx.header64 { 8 } else { 4 };
    let word = |i: usize| -> std::result::Result<u64, String> {
        let s = b
            .get(i * hs..(i + 1) * hs)
            .ok_or_else(|| format!("header truncated ({} bytes, word {i} needed)", b.len()))?;
        let mut v = [0u8; 8];
        if ctx.big_endian {
            v[8 - hs..].copy_from_slice(s);
            Ok(u64::from_be_bytes(v))
        } else {
            v[..hs].copy_from_slice(s);
            Ok(u64::from_le_bytes(v))
        }
    };
    if !ctx.compressed {
        let n = word(0)?;
        if n != want as u64 {
            return Err(format!("header says {n} bytes, expected {want}"));
        }
        return b.get(hs..hs + want).map(<[u8]>::to_vec).ok_or_else(|| {
            format!(
                "data truncated: {} of {want} bytes present",
                b.len().saturating_sub(hs)
            )
        });
    }
    let nb = word(0)?;
    let bs = word(1)?;
    let last = word(2)?;
    let total = match nb {
        0 => 0,
        n => (n - 1)
            .saturating_mul(bs)
            .saturating_add(if last > 0 { last } else { bs }),
    };
    if total != want as u64 {
        return Err(format!(
            "compressed header says {nb} blocks of {bs} bytes (last {last}) = {total} bytes, expected {want}"
        ));
    }
    let nb = nb as usize; // bounded: total == want, so nb <= want + 1
    let mut pos = (3 + nb) * hs;
    let mut out = Vec::with_capacity(want);
    for i in 0..nb {
        let cs = word(3 + i)? as usize;
        let src = b
            .get(pos..pos.saturating_add(cs))
            .ok_or_else(|| format!("compressed block {i} truncated"))?;
        let expect = if i + 1 == nb && last > 0 { last } else { bs } as usize;
        let before = out.len();
        flate2::read::ZlibDecoder::new(src)
            .take(expect as u64)
            .read_to_end(&mut out)
            .map_err(|e| format!("zlib block {i}: {e}"))?;
        if out.len() - before != expect {
            return Err(format!(
                "zlib block {i} inflates to {} bytes, expected {expect}",
                out.len() - before
            ));
        }
        pos += cs;
    }
    Ok(out)
}

/// Decodes base64 that may be several separately padded chunks back to back (VTK encodes the
/// compression header and the data separately); whitespace is ignored.
fn b64(text: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let clean: Vec<u8> = text
        .iter()
        .copied()
        .filter(|c| !c.is_ascii_whitespace())
        .collect();
    if !clean.len().is_multiple_of(4) {
        return Err(format!(
            "base64 text of {} characters is not a multiple of 4",
            clean.len()
        ));
    }
    let eng = base64::engine::general_purpose::STANDARD;
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    let mut start = 0;
    for g in (0..clean.len()).step_by(4) {
        if clean[g..g + 4].contains(&b'=') || g + 4 == clean.len() {
            eng.decode_vec(&clean[start..g + 4], &mut out)
                .map_err(|e| format!("bad base64: {e}"))?;
            start = g + 4;
        }
    }
    Ok(out)
}

fn to_f64(raw: &[u8], ty: &str, size: usize, big: bool) -> Vec<f64> {
    raw.chunks_exact(size)
        .map(|c| {
            let mut b = [0u8; 8];
            b[..size].copy_from_slice(c);
            if big {
                b[..size].reverse();
            }
            // `b` now holds the value little-endian in its first `size` bytes.
            match ty {
                "Int8" | "Char" => b[0] as i8 as f64,
                "UInt8" => b[0] as f64,
                "Int16" => i16::from_le_bytes([b[0], b[1]]) as f64,
                "UInt16" => u16::from_le_bytes([b[0], b[1]]) as f64,
                "Int32" => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                "UInt32" => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                "Float32" => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                "Int64" => i64::from_le_bytes(b) as f64,
                "UInt64" => u64::from_le_bytes(b) as f64,
                _ => f64::from_le_bytes(b),
            }
        })
        .collect()
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}
