//! Legacy VTK (`.vtk`) POLYDATA reader, ASCII and BINARY (big-endian): `POINTS` (any numeric
//! type), `POLYGONS` and `TRIANGLE_STRIPS` in the classic `n i j k …` layout or the VTK 5.1+
//! `OFFSETS`/`CONNECTIVITY` layout, `VERTICES`/`LINES` (counted for cell numbering only), and
//! `POINT_DATA`/`CELL_DATA` with `SCALARS` (+ `LOOKUP_TABLE`) or `FIELD` arrays; the
//! one-component array of a given name, or else of a known label name (see
//! [`super::labels`]), becomes the labels. Other attributes (vectors, normals, texture
//! coordinates, colours, tensors, ids, lookup tables, metadata) are skipped.

use super::labels::{ArrayInfo, MeshFile, choose};
use super::{FaceBuilder, check_finite, check_vertex_count, label_from_f64};
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result};
use glam::DVec3;

struct Lex<'a> {
    b: &'a [u8],
    pos: usize,
    file: &'a str,
    binary: bool,
}

impl<'a> Lex<'a> {
    fn err(&self, m: impl std::fmt::Display) -> Error {
        let line = 1 + self.b[..self.pos.min(self.b.len())]
            .iter()
            .filter(|&&c| c == b'\n')
            .count();
        Error::Io(format!(
            "{}: line {line} (byte {}): {m}",
            self.file, self.pos
        ))
    }

    fn skip_ws(&mut self) {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The next line holding at least one token, split into tokens (`None` at end of file).
    /// Lines of whitespace only (including Unicode whitespace such as a vertical tab, which
    /// `skip_ws` does not skip) are passed over, so a returned line is never empty.
    fn line(&mut self) -> Option<Vec<String>> {
        loop {
            self.skip_ws();
            if self.pos >= self.b.len() {
                return None;
            }
            let end = self.b[self.pos..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(self.b.len(), |e| self.pos + e);
            let text = String::from_utf8_lossy(&self.b[self.pos..end]).into_owned();
            self.pos = (end + 1).min(self.b.len());
            let tokens: Vec<String> = text.split_whitespace().map(str::to_string).collect();
            if !tokens.is_empty() {
                return Some(tokens);
            }
        }
    }

    /// The next line without skipping blank lines (header lines).
    fn raw_line(&mut self) -> Option<String> {
        if self.pos >= self.b.len() {
            return None;
        }
        let end = self.b[self.pos..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(self.b.len(), |e| self.pos + e);
        let text = String::from_utf8_lossy(&self.b[self.pos..end])
            .trim()
            .to_string();
        self.pos = (end + 1).min(self.b.len());
        Some(text)
    }

    /// Reads `n` values of legacy type `ty` (text tokens, or big-endian binary).
    fn values(&mut self, n: usize, ty: &str, what: &str) -> Result<Vec<f64>> {
        let ty = ty.to_ascii_lowercase();
        let size = match ty.as_str() {
            "unsigned_char" | "char" | "vtktypeint8" | "vtktypeuint8" => 1,
            "short" | "unsigned_short" | "vtktypeint16" | "vtktypeuint16" => 2,
            "int" | "unsigned_int" | "float" | "vtktypeint32" | "vtktypeuint32" => 4,
            "long" | "unsigned_long" | "double" | "vtktypeint64" | "vtktypeuint64"
            | "vtkidtype" => 8,
            _ => return Err(self.err(format!("{what}: unsupported data type {ty:?}"))),
        };
        if !self.binary {
            // Every value takes at least one byte plus a separator, so what is left of the file
            // bounds the allocation, whatever count the header declares.
            let mut v =
                Vec::with_capacity(n.min((self.b.len() - self.pos.min(self.b.len())) / 2 + 1));
            for i in 0..n {
                self.skip_ws();
                let start = self.pos;
                while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
                    self.pos += 1;
                }
                if start == self.pos {
                    return Err(self.err(format!("{what}: file ends after {i} of {n} values")));
                }
                let t = String::from_utf8_lossy(&self.b[start..self.pos]);
                let x: f64 = t
                    .parse()
                    .map_err(|_| self.err(format!("{what}: value {i} = {t:?} is not a number")))?;
                v.push(x);
            }
            return Ok(v);
        }
        let len = n.saturating_mul(size);
        let Some(raw) = self.b.get(self.pos..self.pos.saturating_add(len)) else {
            return Err(self.err(format!(
                "{what}: binary data truncated: {n} values of {size} bytes need {len} bytes, {} left",
                self.b.len() - self.pos
            )));
        };
        self.pos += len;
        Ok(raw
            .chunks_exact(size)
            .map(|c| {
                let mut b = [0u8; 8];
                b[8 - size..].copy_from_slice(c);
                let u = u64::from_be_bytes(b);
                match ty.as_str() {
                    "char" | "vtktypeint8" => u as u8 as i8 as f64,
                    "short" | "vtktypeint16" => u as u16 as i16 as f64,
                    "int" | "vtktypeint32" => u as u32 as i32 as f64,
                    "float" => f32::from_bits(u as u32) as f64,
                    "double" => f64::from_bits(u),
                    "long" | "vtktypeint64" | "vtkidtype" => u as i64 as f64,
                    _ => u as f64,
                }
            })
            .collect())
    }
}

struct CellBlock {
    /// Polygons (or strips) as index lists.
    cells: Vec<Vec<i64>>,
}

/// Reads a legacy VTK POLYDATA file held in memory; `file` names it in error messages.
pub fn read_vtk_legacy_bytes(file: &str, bytes: &[u8]) -> Result<LabeledMesh> {
    read_vtk_legacy_bytes_with(file, bytes, None).map(|f| f.mesh)
}

/// Like [`read_vtk_legacy_bytes`], with the labels from the array named `label_array` (point
/// or cell data) instead of the automatic choice, and the arrays found.
pub fn read_vtk_legacy_bytes_with(
    file: &str,
    bytes: &[u8],
    label_array: Option<&str>,
) -> Result<MeshFile> {
    let mut lx = Lex {
        b: bytes,
        pos: 0,
        file,
        binary: false,
    };
    read_header(&mut lx)?;
    let mut points: Vec<DVec3> = Vec::new();
    let mut blocks: [Option<CellBlock>; 4] = [None, None, None, None]; // verts, lines, polys, strips
    let mut domain: Option<(bool, usize)> = None; // (is_point_data, count)
    // Every one-component array with its values, in file order.
    let mut scalars: Vec<(ArrayInfo, Vec<f64>)> = Vec::new();
    while let Some(t) = lx.line() {
        let kw = t[0].to_ascii_uppercase();
        match kw.as_str() {
            "POINTS" => {
                let n = count_at(&lx, &t, 1, "POINTS")?;
                let ty = t.get(2).cloned().unwrap_or_default();
                let v = lx.values(n.saturating_mul(3), &ty, "POINTS")?;
                points = v
                    .chunks_exact(3)
                    .map(|c| DVec3::new(c[0], c[1], c[2]))
                    .collect();
            }
            "VERTICES" | "LINES" | "POLYGONS" | "TRIANGLE_STRIPS" => {
                let slot = ["VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS"]
                    .iter()
                    .position(|k| *k == kw)
                    .unwrap_or(0);
                blocks[slot] = Some(read_cells(&mut lx, &t, &kw)?);
            }
            "POINT_DATA" | "CELL_DATA" => {
                domain = Some((kw == "POINT_DATA", count_at(&lx, &t, 1, &kw)?));
            }
            "SCALARS"
            | "FIELD"
            | "VECTORS"
            | "NORMALS"
            | "TEXTURE_COORDINATES"
            | "COLOR_SCALARS"
            | "TENSORS"
            | "GLOBAL_IDS"
            | "PEDIGREE_IDS"
            | "LOOKUP_TABLE" => {
                let Some((is_point, n)) = domain else {
                    return Err(lx.err(format!("{kw} before POINT_DATA or CELL_DATA")));
                };
                for (name, ty, comps, v) in read_attribute(&mut lx, &t, &kw, n)? {
                    if comps == 1 {
                        scalars.push((ArrayInfo::new(&name, is_point, &ty), v));
                    }
                }
            }
            "METADATA" => {
                // Text block ended by a blank line.
                while let Some(l) = lx.raw_line() {
                    if l.is_empty() {
                        break;
                    }
                }
            }
            _ => return Err(lx.err(format!("unexpected keyword {:?}", t[0]))),
        }
    }
    assemble(file, points, &blocks, scalars, label_array)
}

/// The three header lines (version, title, ASCII/BINARY) and `DATASET POLYDATA`.
fn read_header(lx: &mut Lex) -> Result<()> {
    let l1 = lx.raw_line().unwrap_or_default();
    if !l1.starts_with("# vtk DataFile") {
        return Err(lx.err("not a legacy VTK file (expected `# vtk DataFile Version x.y`)"));
    }
    let _title = lx.raw_line();
    match lx
        .raw_line()
        .unwrap_or_default()
        .to_ascii_uppercase()
        .as_str()
    {
        "ASCII" => {}
        "BINARY" => lx.binary = true,
        other => return Err(lx.err(format!("third line is {other:?}, expected ASCII or BINARY"))),
    }
    match lx.line() {
        Some(t) if t.len() >= 2 && t[0].eq_ignore_ascii_case("DATASET") => {
            if !t[1].eq_ignore_ascii_case("POLYDATA") {
                return Err(lx.err(format!("DATASET {} is not supported (only POLYDATA)", t[1])));
            }
            Ok(())
        }
        _ => Err(lx.err("expected `DATASET POLYDATA`")),
    }
}

/// Item `i` of the keyword line `t` as a count.
fn count_at(lx: &Lex, t: &[String], i: usize, what: &str) -> Result<usize> {
    t.get(i)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| lx.err(format!("{what}: expected a count as item {i} of {t:?}")))
}

/// A cell block (`kw n size` line `t` read): the classic layout (count, then indices, per cell)
/// or the VTK 5.1 one (OFFSETS, then CONNECTIVITY).
fn read_cells(lx: &mut Lex, t: &[String], kw: &str) -> Result<CellBlock> {
    let n = count_at(lx, t, 1, kw)?;
    let size = count_at(lx, t, 2, kw)?;
    let save = lx.pos;
    let cells = match lx.line() {
        Some(o) if o[0].eq_ignore_ascii_case("OFFSETS") => {
            let oty = o.get(1).cloned().unwrap_or_default();
            let offs = lx.values(n, &oty, "OFFSETS")?;
            let c = lx.line().unwrap_or_default();
            if c.first()
                .is_none_or(|k| !k.eq_ignore_ascii_case("CONNECTIVITY"))
            {
                return Err(lx.err(format!("{kw}: expected CONNECTIVITY after OFFSETS")));
            }
            let cty = c.get(1).cloned().unwrap_or_default();
            let conn = lx.values(size, &cty, "CONNECTIVITY")?;
            split_offsets(lx, kw, &offs, &conn)?
        }
        _ => {
            lx.pos = save;
            let data = lx.values(size, "int", kw)?;
            split_classic(lx, kw, n, &data)?
        }
    };
    Ok(CellBlock { cells })
}

/// An array of an attribute: name, type, components, values.
type Attribute = (String, String, usize, Vec<f64>);

/// One attribute of a POINT_DATA or CELL_DATA section of `n` tuples (keyword line `t` read):
/// its arrays as (name, type, components, values); the attributes that cannot carry labels
/// (vectors, normals, tensors, ids, texture coordinates, colours, lookup tables) are read past
/// and give none.
fn read_attribute(lx: &mut Lex, t: &[String], kw: &str, n: usize) -> Result<Vec<Attribute>> {
    let mut found = Vec::new();
    match kw {
        "SCALARS" => {
            let name = t.get(1).cloned().unwrap_or_default();
            let ty = t.get(2).cloned().unwrap_or_default();
            let comps = match t.get(3) {
                Some(_) => count_at(lx, t, 3, "SCALARS")?,
                None => 1,
            };
            let save = lx.pos;
            match lx.line() {
                Some(l) if l[0].eq_ignore_ascii_case("LOOKUP_TABLE") => {}
                _ => lx.pos = save,
            }
            let v = lx.values(n.saturating_mul(comps), &ty, &format!("SCALARS {name}"))?;
            found.push((name, ty, comps, v));
        }
        "FIELD" => {
            let k = count_at(lx, t, 2, "FIELD")?;
            for _ in 0..k {
                let a = lx.line().unwrap_or_default();
                if a.first()
                    .is_some_and(|s| s.eq_ignore_ascii_case("NULL_ARRAY"))
                {
                    continue;
                }
                let comps = count_at(lx, &a, 1, "FIELD array")?;
                let tuples = count_at(lx, &a, 2, "FIELD array")?;
                let ty = a.get(3).cloned().unwrap_or_default();
                let name = a[0].clone();
                let v = lx.values(comps.saturating_mul(tuples), &ty, &name)?;
                if tuples == n {
                    found.push((name, ty, comps, v));
                }
            }
        }
        "VECTORS" | "NORMALS" => {
            lx.values(n.saturating_mul(3), t.get(2).map_or("", |s| s), kw)?;
        }
        "TENSORS" => {
            lx.values(n.saturating_mul(9), t.get(2).map_or("", |s| s), kw)?;
        }
        "GLOBAL_IDS" | "PEDIGREE_IDS" => {
            lx.values(n, t.get(2).map_or("", |s| s), kw)?;
        }
        "TEXTURE_COORDINATES" => {
            let d = count_at(lx, t, 2, kw)?;
            lx.values(n.saturating_mul(d), t.get(3).map_or("", |s| s), kw)?;
        }
        "COLOR_SCALARS" => {
            let d = count_at(lx, t, 2, kw)?;
            let ty = if lx.binary { "unsigned_char" } else { "float" };
            lx.values(n.saturating_mul(d), ty, kw)?;
        }
        _ => {
            // A standalone LOOKUP_TABLE name size: size RGBA entries.
            let size = count_at(lx, t, 2, kw)?;
            let ty = if lx.binary { "unsigned_char" } else { "float" };
            lx.values(size.saturating_mul(4), ty, kw)?;
        }
    }
    Ok(found)
}

/// The mesh from the points, the polygon and strip blocks (triangulated), and the label array
/// chosen among the one-component `scalars` (`label_array`, or by name).
fn assemble(
    file: &str,
    points: Vec<DVec3>,
    blocks: &[Option<CellBlock>; 4],
    mut scalars: Vec<(ArrayInfo, Vec<f64>)>,
    label_array: Option<&str>,
) -> Result<MeshFile> {
    check_vertex_count(file, points.len())?;
    check_finite(file, &points)?;
    let mut fb = FaceBuilder::new(file, points.len());
    let count = |k: usize| blocks[k].as_ref().map_or(0, |b| b.cells.len());
    let first_poly_cell = count(0) + count(1);
    for (k, b) in blocks.iter().enumerate().skip(2) {
        for c in b.iter().flat_map(|b| &b.cells) {
            if k == 2 { fb.polygon(c)? } else { fb.strip(c)? }
        }
    }
    let n_cells = first_poly_cell + count(2) + count(3);
    let arrays: Vec<ArrayInfo> = scalars.iter().map(|(a, _)| a.clone()).collect();
    let chosen = choose(file, &arrays, label_array)?;
    let mut take = |on_points: bool| {
        let name = chosen.as_deref()?;
        let i = scalars
            .iter()
            .position(|(a, _)| a.on_points == on_points && a.name == name)?;
        Some(std::mem::take(&mut scalars[i].1))
    };
    let (plab, clab) = (take(true), take(false));
    let vertex_labels = match plab {
        Some(v) => {
            if v.len() != points.len() {
                return Err(Error::Io(format!(
                    "{file}: POINT_DATA has {} values for {} points",
                    v.len(),
                    points.len()
                )));
            }
            Some(to_labels(file, &v, "vertex")?)
        }
        None => None,
    };
    let face_labels = match clab {
        Some(v) => {
            if v.len() != n_cells {
                return Err(Error::Io(format!(
                    "{file}: CELL_DATA has {} values for {n_cells} cells",
                    v.len()
                )));
            }
            let l = to_labels(file, &v, "cell")?;
            Some(
                fb.source_poly
                    .iter()
                    .map(|&c| l[first_poly_cell + c as usize])
                    .collect(),
            )
        }
        None => None,
    };
    let found = vertex_labels.is_some() || face_labels.is_some();
    Ok(MeshFile {
        mesh: LabeledMesh {
            mesh: TriMesh::new(points, fb.triangles),
            vertex_labels,
            face_labels,
        },
        label_array: chosen.filter(|_| found),
        teeth3ds_json: false,
        arrays,
    })
}

fn to_labels(file: &str, v: &[f64], what: &str) -> Result<Vec<i32>> {
    v.iter()
        .enumerate()
        .map(|(i, &x)| label_from_f64(x, file, what, i))
        .collect()
}

fn as_index(x: f64) -> i64 {
    if x.fract() == 0.0 && x.abs() < 9e15 {
        x as i64
    } else {
        -1
    }
}

/// Classic layout: `n` cells, each `count i0 i1 …`, `data` holding exactly all of them.
fn split_classic(lx: &Lex, kw: &str, n: usize, data: &[f64]) -> Result<Vec<Vec<i64>>> {
    let mut cells = Vec::with_capacity(n.min(data.len()));
    let mut i = 0;
    for c in 0..n {
        let k = data.get(i).copied().map(as_index).unwrap_or(-1);
        if k < 0 || i + 1 + k as usize > data.len() {
            return Err(lx.err(format!(
                "{kw}: cell {c} claims {k} vertices but only {} values remain (size field wrong?)",
                data.len().saturating_sub(i + 1)
            )));
        }
        let k = k as usize;
        cells.push(
            data[i + 1..i + 1 + k]
                .iter()
                .map(|&x| as_index(x))
                .collect(),
        );
        i += 1 + k;
    }
    if i != data.len() {
        return Err(lx.err(format!(
            "{kw}: {n} cells use {i} values but the size field says {}",
            data.len()
        )));
    }
    Ok(cells)
}

/// VTK 5.1+ layout: `offsets` (cells + 1, starting at 0) into `conn`.
fn split_offsets(lx: &Lex, kw: &str, offs: &[f64], conn: &[f64]) -> Result<Vec<Vec<i64>>> {
    let mut cells = Vec::with_capacity(offs.len().saturating_sub(1));
    for (c, w) in offs.windows(2).enumerate() {
        let (a, b) = (as_index(w[0]), as_index(w[1]));
        if a < 0 || b < a || b as usize > conn.len() {
            return Err(lx.err(format!(
                "{kw}: offsets {c}..{} = {}..{} do not index the {} connectivity values",
                c + 1,
                w[0],
                w[1],
                conn.len()
            )));
        }
        cells.push(
            conn[a as usize..b as usize]
                .iter()
                .map(|&x| as_index(x))
                .collect(),
        );
    }
    Ok(cells)
}
