//! VTK XML PolyData (`.vtp`) reader. Supports every encoding VTK writes: `ascii`, inline
//! `binary` (base64) and `appended` (raw or base64), each with a `UInt32` or `UInt64` header
//! and with or without `vtkZLibDataCompressor` block compression; any byte order; several
//! pieces (merged). Geometry: `Points` (Float32/Float64), `Polys` (fan-triangulated) and
//! `Strips` (split into triangles); `Verts`/`Lines` only count towards cell numbering.
//! Labels: the `PointData`/`CellData` array of a given name, or else of a known label name
//! (see [`super::labels`]; any numeric type).
//!
//! The XML part is parsed by `quick-xml`; the appended block (raw bytes are not XML) is cut
//! off first and addressed by the arrays' `offset` attributes.

use super::labels::{ArrayInfo, MeshFile, choose};
use super::vtp_data::{BlockFormat, b64, block, to_f64, type_size};
use super::{FaceBuilder, check_finite, check_vertex_count, label_from_f64};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result};
use glam::DVec3;
use quick_xml::events::{BytesStart, Event};

pub use super::vtp_write::{VtpEncoding, write_vtp};

/// Largest point or cell count accepted from a header (keeps size arithmetic far from overflow).
const MAX_COUNT: usize = 1 << 40;

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
    fmt: BlockFormat,
    appended_base64: bool,
    /// The appended block after its leading `_`.
    appended: &'a [u8],
    /// Sorted distinct offsets of all appended arrays (to find where a base64 array ends).
    offsets: Vec<usize>,
}

/// Reads a VTK XML PolyData file held in memory; `file` names it in error messages.
pub fn read_vtp_bytes(file: &str, bytes: &[u8]) -> Result<LabeledMesh> {
    read_vtp_bytes_with(file, bytes, None).map(|f| f.mesh)
}

/// Like [`read_vtp_bytes`], with the labels from the array named `label_array` (point or cell
/// data) instead of the automatic choice, and the arrays found.
pub fn read_vtp_bytes_with(
    file: &str,
    bytes: &[u8],
    label_array: Option<&str>,
) -> Result<MeshFile> {
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let app_pos = find(bytes, b"<AppendedData");
    let xml = &bytes[..app_pos.unwrap_or(bytes.len())];
    let mut rd = quick_xml::Reader::from_reader(xml);
    rd.config_mut().check_end_names = false;
    let mut ctx = Ctx {
        file,
        fmt: BlockFormat::default(),
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
                        ctx.fmt = file_format(file, e)?;
                    }
                    "Piece" => pieces.push(piece(file, e)?),
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
        (ctx.appended_base64, ctx.appended) = appended_block(file, &bytes[p..])?;
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
    assemble(&ctx, &pieces, label_array)
}

/// The byte order, header size and compression named by the `<VTKFile>` element (which must
/// be of type PolyData).
fn file_format(file: &str, e: &BytesStart) -> Result<BlockFormat> {
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let ty = attr(e, "type")?.unwrap_or_default();
    if ty != "PolyData" {
        return Err(err(format!(
            "VTKFile type is {ty:?}; only PolyData is supported"
        )));
    }
    let mut fmt = BlockFormat::default();
    fmt.big_endian = attr(e, "byte_order")?.as_deref() == Some("BigEndian");
    fmt.header64 = match attr(e, "header_type")?.as_deref() {
        None | Some("UInt32") => false,
        Some("UInt64") => true,
        Some(h) => {
            return Err(err(format!(
                "header_type {h:?} (expected UInt32 or UInt64)"
            )));
        }
    };
    fmt.compressed = match attr(e, "compressor")?.as_deref() {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(c) => {
            return Err(err(format!(
                "compressor {c:?} is not supported (only vtkZLibDataCompressor)"
            )));
        }
    };
    Ok(fmt)
}

/// A `<Piece>` element's counts (each at most `MAX_COUNT`; a missing one is 0).
fn piece(file: &str, e: &BytesStart) -> Result<Piece> {
    let n = |k: &str| -> Result<usize> {
        match attr(e, k)? {
            None => Ok(0),
            Some(v) => match v.trim().parse::<usize>() {
                Ok(c) if c <= MAX_COUNT => Ok(c),
                _ => Err(Error::Io(format!(
                    "{file}: Piece attribute {k}={v:?} is not a plausible count"
                ))),
            },
        }
    };
    Ok(Piece {
        points: n("NumberOfPoints")?,
        verts: n("NumberOfVerts")?,
        lines: n("NumberOfLines")?,
        polys: n("NumberOfPolys")?,
        strips: n("NumberOfStrips")?,
        arrays: Vec::new(),
    })
}

/// The `<AppendedData>` element starting `tail`: whether it is base64, and its block after
/// the leading `_` (for base64, up to the next `<`).
fn appended_block<'a>(file: &str, tail: &'a [u8]) -> Result<(bool, &'a [u8])> {
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let gt = find(tail, b">").ok_or_else(|| err("unterminated <AppendedData> tag".into()))?;
    let tag = String::from_utf8_lossy(&tail[..gt]);
    let base64 = if tag.contains("\"base64\"") {
        true
    } else if tag.contains("\"raw\"") {
        false
    } else {
        return Err(err(format!(
            "<AppendedData> encoding missing or unknown in `{tag}>` (expected raw or base64)"
        )));
    };
    let us =
        find(&tail[gt..], b"_").ok_or_else(|| err("appended data lacks its leading `_`".into()))?;
    let mut block = &tail[gt + us + 1..];
    if base64 {
        let end = find(block, b"<").unwrap_or(block.len());
        block = &block[..end];
    }
    Ok((base64, block))
}

fn assemble(ctx: &Ctx, pieces: &[Piece], label_array: Option<&str>) -> Result<MeshFile> {
    let file = ctx.file;
    let mut arrays: Vec<ArrayInfo> = Vec::new();
    for a in pieces.iter().flat_map(|p| &p.arrays) {
        let on_points = match a.section {
            Section::PointData => true,
            Section::CellData => false,
            _ => continue,
        };
        let info = ArrayInfo::new(&a.name, on_points, &a.ty);
        if a.components == 1 && !arrays.contains(&info) {
            arrays.push(info);
        }
    }
    let chosen = choose(file, &arrays, label_array)?;
    let ch = chosen.as_deref();
    let err = |m: String| Error::Io(format!("{file}: {m}"));
    let mut positions: Vec<DVec3> = Vec::new();
    let mut triangles = Vec::new();
    let (mut vlabels, mut flabels): (Option<Vec<i32>>, Option<Vec<i32>>) = (None, None);
    let all_have = |s: Section| {
        pieces
            .iter()
            .all(|p| pick_label(p, s, ch).is_some() || count_of(p, s) == 0)
    };
    let use_v = pieces
        .iter()
        .any(|p| pick_label(p, Section::PointData, ch).is_some())
        && all_have(Section::PointData);
    let use_f = pieces
        .iter()
        .any(|p| pick_label(p, Section::CellData, ch).is_some())
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
            let a = pick_label(p, Section::PointData, ch);
            let vals = match a {
                Some(a) => labels_of(ctx, a, p.points, "vertex")?,
                None => Vec::new(),
            };
            vlabels.get_or_insert_with(Vec::new).extend(vals);
        }
        if use_f {
            let vals = match pick_label(p, Section::CellData, ch) {
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
    let found = vlabels.is_some() || flabels.is_some();
    Ok(MeshFile {
        mesh: LabeledMesh {
            mesh: TriMesh::new(positions, triangles),
            vertex_labels: vlabels,
            face_labels: flabels,
        },
        label_array: chosen.filter(|_| found),
        teeth3ds_json: false,
        arrays,
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

/// The array named `name` in section `s` of a piece.
fn pick_label<'p>(p: &'p Piece, s: Section, name: Option<&str>) -> Option<&'p ArrayDesc> {
    let name = name?;
    p.arrays.iter().find(|a| a.section == s && a.name == name)
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
            block(ctx.fmt, &bytes, values * size).map_err(&err)?
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
                block(ctx.fmt, &bytes, values * size).map_err(&err)?
            } else {
                block(ctx.fmt, &ctx.appended[a.offset..], values * size)
                    .map_err(|m| err(format!("at appended offset {}: {m}", a.offset)))?
            }
        }
    };
    Ok(to_f64(&raw, &a.ty, size, ctx.fmt.big_endian))
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}
