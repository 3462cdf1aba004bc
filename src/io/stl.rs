//! STL, binary and ASCII. Triangles arrive as separate corners; identical corners (exact f32
//! coordinates, `-0.0` = `0.0`) are welded in order of first occurrence so the topology is usable.
//!
//! Binary is recognised by its exact size (84 + 50 · count bytes), so binary files whose
//! 80-byte header happens to start with `solid` still read correctly; ASCII goes through the
//! `stl_io` crate.

use crate::mesh::TriMesh;
use crate::{Error, Result};
use glam::DVec3;
use std::collections::HashMap;
use std::io::Write;

/// Reads an STL file held in memory; `file` names it in error messages.
pub fn read_stl_bytes(file: &str, bytes: &[u8]) -> Result<TriMesh> {
    let binary_count = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let is_binary = binary_count.is_some_and(|n| 84 + 50 * n == bytes.len() as u64);
    let mut welder = Welder::default();
    if is_binary {
        for rec in bytes[84..].chunks_exact(50) {
            let f = |o: usize| f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
            let c = |o: usize| [f(o), f(o + 4), f(o + 8)];
            welder.triangle([c(12), c(24), c(36)]);
        }
    } else if bytes.starts_with(b"solid") {
        let mut cur = std::io::Cursor::new(bytes);
        let iter = stl_io::create_stl_reader(&mut cur)
            .map_err(|e| Error::Io(format!("{file}: malformed ASCII STL: {e}")))?;
        for (i, t) in iter.enumerate() {
            let t = t.map_err(|e| {
                Error::Io(format!(
                    "{file}: malformed ASCII STL at facet {i} (expected `facet normal nx ny nz`, \
                     `outer loop`, three `vertex x y z`, `endloop`, `endfacet`): {e}"
                ))
            })?;
            welder.triangle(t.vertices.map(|v| v.0));
        }
    } else {
        return Err(Error::Io(match binary_count {
            Some(n) => format!(
                "{file}: not a valid binary STL: header says {n} triangles = {} bytes, but the file has {} bytes (truncated or not STL)",
                84 + 50 * n,
                bytes.len()
            ),
            None => format!(
                "{file}: not an STL file: {} bytes, shorter than the 84-byte binary header and not starting with `solid`",
                bytes.len()
            ),
        }));
    }
    let mesh = TriMesh::new(welder.positions, welder.triangles);
    super::check_finite(file, &mesh.positions)?;
    Ok(mesh)
}

#[derive(Default)]
struct Welder {
    map: HashMap<[u32; 3], u32>,
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
}

impl Welder {
    fn triangle(&mut self, corners: [[f32; 3]; 3]) {
        let t = corners.map(|c| {
            // Normalise -0.0 to 0.0 so the two zeros weld; lookups only, order = first use.
            let key = c.map(|x| if x == 0.0 { 0u32 } else { x.to_bits() });
            let next = self.positions.len() as u32;
            *self.map.entry(key).or_insert_with(|| {
                self.positions
                    .push(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64));
                next
            })
        });
        self.triangles.push(t);
    }
}

/// Writes a binary STL (f32 coordinates, face normals from the geometry; no properties).
pub fn write_stl(out: &mut impl Write, mesh: &TriMesh) -> Result<()> {
    super::check_mesh_indices(mesh)?;
    let f = |p: DVec3| stl_io::Vector::new([p.x as f32, p.y as f32, p.z as f32]);
    let tris: Vec<stl_io::Triangle> = (0..mesh.face_count())
        .map(|i| {
            let [a, b, c] = mesh.corners(i);
            stl_io::Triangle {
                normal: f((b - a).cross(c - a).normalize_or_zero()),
                vertices: [f(a), f(b), f(c)],
            }
        })
        .collect();
    stl_io::write_stl(out, tris.iter()).map_err(|e| Error::Io(format!("writing STL: {e}")))
}
