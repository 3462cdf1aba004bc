//! VTK XML PolyData (`.vtp`) writer in every encoding the reader accepts (used by
//! [`super::write_mesh`] and by the round-trip tests): points as Float64, triangles as Int64
//! `connectivity`/`offsets`, integer properties as Int32 point or cell data.

use crate::mesh::TriMesh;
use crate::{Error, Result};
use base64::Engine;
use std::io::Write;

/// How [`write_vtp`] encodes the data arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VtpEncoding {
    /// `format="ascii"`: decimal text (shortest round-trip, lossless).
    Ascii,
    /// `format="binary"`: base64 inline in each DataArray.
    Binary {
        /// zlib-compress in blocks (`vtkZLibDataCompressor`).
        compressed: bool,
        /// `header_type="UInt64"` instead of UInt32.
        header64: bool,
    },
    /// `format="appended"` with `<AppendedData encoding="raw">`.
    AppendedRaw {
        /// zlib-compress in blocks.
        compressed: bool,
        /// `header_type="UInt64"` instead of UInt32.
        header64: bool,
    },
    /// `format="appended"` with `<AppendedData encoding="base64">`.
    AppendedBase64 {
        /// zlib-compress in blocks.
        compressed: bool,
        /// `header_type="UInt64"` instead of UInt32.
        header64: bool,
    },
}

/// Uncompressed block size for zlib compression (VTK's default is 32 KiB; smaller here so
/// that test meshes span several blocks).
const BLOCK: usize = 16 * 1024;

enum Data<'a> {
    F64(&'a [f64]),
    I64(Vec<i64>),
    I32(&'a [i32]),
}

impl Data<'_> {
    fn type_name(&self) -> &'static str {
        match self {
            Data::F64(_) => "Float64",
            Data::I64(_) => "Int64",
            Data::I32(_) => "Int32",
        }
    }
    fn bytes(&self) -> Vec<u8> {
        match self {
            Data::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Data::I64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Data::I32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    }
    fn ascii(&self) -> String {
        let mut s = String::new();
        use std::fmt::Write as _;
        match self {
            Data::F64(v) => v.iter().for_each(|x| {
                let _ = write!(s, "{x} ");
            }),
            Data::I64(v) => v.iter().for_each(|x| {
                let _ = write!(s, "{x} ");
            }),
            Data::I32(v) => v.iter().for_each(|x| {
                let _ = write!(s, "{x} ");
            }),
        }
        s
    }
}

/// Writes `mesh` as VTK XML PolyData with Int32 point data `point_int_props` and cell data
/// `cell_int_props` (one value per triangle), in the given encoding (little-endian).
pub fn write_vtp(
    out: &mut impl Write,
    mesh: &TriMesh,
    point_int_props: &[(&str, &[i32])],
    cell_int_props: &[(&str, &[i32])],
    encoding: VtpEncoding,
) -> Result<()> {
    super::check_mesh_indices(mesh)?;
    for (name, v) in point_int_props {
        if v.len() != mesh.vertex_count() {
            return Err(Error::InvalidArgument(format!(
                "point property {name:?}: {} values for {} vertices",
                v.len(),
                mesh.vertex_count()
            )));
        }
    }
    for (name, v) in cell_int_props {
        if v.len() != mesh.face_count() {
            return Err(Error::InvalidArgument(format!(
                "cell property {name:?}: {} values for {} faces",
                v.len(),
                mesh.face_count()
            )));
        }
    }
    let (compressed, header64) = match encoding {
        VtpEncoding::Ascii => (false, false),
        VtpEncoding::Binary {
            compressed,
            header64,
        }
        | VtpEncoding::AppendedRaw {
            compressed,
            header64,
        }
        | VtpEncoding::AppendedBase64 {
            compressed,
            header64,
        } => (compressed, header64),
    };
    let pts: Vec<f64> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
    let conn = Data::I64(mesh.triangles.iter().flatten().map(|&v| v as i64).collect());
    let offs = Data::I64((1..=mesh.face_count() as i64).map(|i| 3 * i).collect());

    let mut xml = String::new();
    let mut appended: Vec<u8> = Vec::new();
    let mut array = |xml: &mut String, name: &str, comps: usize, d: &Data| {
        let head = format!(
            "<DataArray type=\"{}\" Name=\"{name}\" NumberOfComponents=\"{comps}\"",
            d.type_name()
        );
        match encoding {
            VtpEncoding::Ascii => {
                xml.push_str(&format!(
                    "{head} format=\"ascii\">{}</DataArray>\n",
                    d.ascii()
                ));
            }
            VtpEncoding::Binary { .. } => {
                let b = encode_b64(&d.bytes(), compressed, header64);
                xml.push_str(&format!("{head} format=\"binary\">{b}</DataArray>\n"));
            }
            VtpEncoding::AppendedRaw { .. } => {
                xml.push_str(&format!(
                    "{head} format=\"appended\" offset=\"{}\"/>\n",
                    appended.len()
                ));
                appended.extend(block(&d.bytes(), compressed, header64).concat());
            }
            VtpEncoding::AppendedBase64 { .. } => {
                xml.push_str(&format!(
                    "{head} format=\"appended\" offset=\"{}\"/>\n",
                    appended.len()
                ));
                appended.extend(encode_b64(&d.bytes(), compressed, header64).bytes());
            }
        }
    };
    let mut doc = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\"",
    );
    doc.push_str(if header64 {
        " header_type=\"UInt64\""
    } else {
        " header_type=\"UInt32\""
    });
    if compressed {
        doc.push_str(" compressor=\"vtkZLibDataCompressor\"");
    }
    doc.push_str(">\n<PolyData>\n");
    doc.push_str(&format!(
        "<Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"{}\">\n",
        mesh.vertex_count(),
        mesh.face_count()
    ));
    xml.push_str("<PointData>\n");
    for (name, v) in point_int_props {
        array(&mut xml, name, 1, &Data::I32(v));
    }
    xml.push_str("</PointData>\n<CellData>\n");
    for (name, v) in cell_int_props {
        array(&mut xml, name, 1, &Data::I32(v));
    }
    xml.push_str("</CellData>\n<Points>\n");
    array(&mut xml, "Points", 3, &Data::F64(&pts));
    xml.push_str("</Points>\n<Polys>\n");
    array(&mut xml, "connectivity", 1, &conn);
    array(&mut xml, "offsets", 1, &offs);
    xml.push_str("</Polys>\n</Piece>\n</PolyData>\n");
    doc.push_str(&xml);
    let mut bytes = doc.into_bytes();
    match encoding {
        VtpEncoding::AppendedRaw { .. } => {
            bytes.extend_from_slice(b"<AppendedData encoding=\"raw\">\n_");
            bytes.extend_from_slice(&appended);
            bytes.extend_from_slice(b"\n</AppendedData>\n");
        }
        VtpEncoding::AppendedBase64 { .. } => {
            bytes.extend_from_slice(b"<AppendedData encoding=\"base64\">\n_");
            bytes.extend_from_slice(&appended);
            bytes.extend_from_slice(b"\n</AppendedData>\n");
        }
        _ => {}
    }
    bytes.extend_from_slice(b"</VTKFile>\n");
    out.write_all(&bytes)
        .map_err(|e| Error::Io(format!("writing VTP: {e}")))
}

/// The binary block of one array: `[header, data]`, the header being the byte count
/// (uncompressed) or `[nblocks, blocksize, lastsize, csize…]` followed by zlib blocks.
fn block(data: &[u8], compressed: bool, header64: bool) -> [Vec<u8>; 2] {
    let word = |v: usize| -> Vec<u8> {
        if header64 {
            (v as u64).to_le_bytes().to_vec()
        } else {
            (v as u32).to_le_bytes().to_vec()
        }
    };
    if !compressed {
        return [word(data.len()), data.to_vec()];
    }
    let chunks: Vec<Vec<u8>> = data
        .chunks(BLOCK)
        .map(|c| {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            // Writing into a Vec cannot fail.
            let _ = z.write_all(c);
            z.finish().unwrap_or_default()
        })
        .collect();
    let last = data.len() % BLOCK;
    let mut head = word(chunks.len());
    head.extend(word(BLOCK));
    head.extend(word(last));
    for c in &chunks {
        head.extend(word(c.len()));
    }
    [head, chunks.concat()]
}

/// Base64 as VTK writes it: header and data encoded separately when compressed, together
/// otherwise.
fn encode_b64(data: &[u8], compressed: bool, header64: bool) -> String {
    let eng = base64::engine::general_purpose::STANDARD;
    let [head, body] = block(data, compressed, header64);
    if compressed {
        eng.encode(head) + &eng.encode(body)
    } else {
        eng.encode([head, body].concat())
    }
}
