//! Measures: face normals and areas, area-weighted vertex normals, signed volume, edge lengths.

use super::TriMesh;
use glam::DVec3;

impl TriMesh {
    /// Unnormalised face normal (twice the area, pointing out for CCW faces).
    #[inline]
    pub fn face_cross(&self, f: usize) -> DVec3 {
        let [a, b, c] = self.corners(f);
        (b - a).cross(c - a)
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|f| 0.5 * self.face_cross(f).length())
            .sum()
    }

    /// Area-weighted vertex normals, unit length (zero for unused vertices).
    pub fn vertex_normals(&self) -> Vec<DVec3> {
        let mut n = vec![DVec3::ZERO; self.positions.len()];
        for (f, t) in self.triangles.iter().enumerate() {
            let c = self.face_cross(f);
            for &v in t {
                n[v as usize] += c;
            }
        }
        for v in &mut n {
            *v = v.normalize_or_zero();
        }
        n
    }

    /// Signed volume enclosed (positive for a closed, outward-oriented surface).
    pub fn signed_volume(&self) -> f64 {
        // Relative to the first vertex for better conditioning far from the origin.
        let o = self.positions.first().copied().unwrap_or(DVec3::ZERO);
        self.triangles
            .iter()
            .map(|t| {
                let a = self.positions[t[0] as usize] - o;
                let b = self.positions[t[1] as usize] - o;
                let c = self.positions[t[2] as usize] - o;
                a.dot(b.cross(c))
            })
            .sum::<f64>()
            / 6.0
    }

    /// Mean edge length over all triangle sides (each interior edge counted twice).
    pub fn mean_edge_length(&self) -> f64 {
        if self.triangles.is_empty() {
            return 0.0;
        }
        let s: f64 = (0..self.triangles.len())
            .map(|f| {
                let [a, b, c] = self.corners(f);
                (b - a).length() + (c - b).length() + (a - c).length()
            })
            .sum();
        s / (3 * self.triangles.len()) as f64
    }

    /// Reverses every triangle's orientation.
    pub fn flip(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::mesh::fixtures::{cube, tetrahedron};
    use glam::DVec3;

    #[test]
    fn volumes_areas_normals() {
        let c = cube(2.0);
        assert!((c.signed_volume() - 8.0).abs() < 1e-12);
        assert!((c.area() - 24.0).abs() < 1e-12);
        let t = tetrahedron();
        assert!((t.signed_volume() - 1.0 / 6.0).abs() < 1e-12);
        let n = c.vertex_normals();
        // Corner (1,1,1): area weights 2 (top), 2 (right), 1 (back; one of its triangles).
        assert!((n[6] - DVec3::new(2.0, 1.0, 2.0).normalize()).length() < 1e-12);
        let mut f = c.clone();
        f.flip();
        assert!((f.signed_volume() + 8.0).abs() < 1e-12);
    }
}
