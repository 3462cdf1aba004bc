//! The faces near the band, binned for the untangling's candidate search: the faces off the
//! band never move while the untangling runs, so they are binned once; only the band faces are
//! binned anew each round.

use super::band_crossings::{Recount, band_region, bbox, overlap};
use crate::mesh::TriMesh;
use crate::mesh_check::TriangleGrid;
use glam::DVec3;
use std::ops::Range;

/// The faces whose boxes meet the band's box grown by two band edges (`scale`), binned in
/// cells of two band edges over the whole mesh's box. A query answers exactly what
/// `TriangleGrid::over` over this round's near faces would: the same grid geometry (the mesh's
/// box and the cell), the same faces in every cell.
#[derive(Default)]
pub(super) struct NearFaces {
    /// The faces off the band, binned once.
    fixed: Option<Fixed>,
    /// This round's band faces, binned.
    band: Option<TriangleGrid>,
    /// This round's region: the band's box grown by two band edges.
    region: (DVec3, DVec3),
}

/// The faces off the band meeting `covered`, binned over the mesh box `all`.
struct Fixed {
    grid: TriangleGrid,
    all: (DVec3, DVec3),
    covered: (DVec3, DVec3),
}

impl NearFaces {
    /// Bins this round's faces: the band faces always, the faces off the band only when the
    /// band's region left the region they were binned for or the mesh's box changed.
    pub(super) fn update(&mut self, mesh: &TriMesh, band: Range<usize>, scale: f64) {
        self.update_band(mesh, band.clone(), scale);
        self.update_fixed(mesh, band, scale);
    }

    /// The band half of [`NearFaces::update`]: this round's band faces binned and its region.
    /// Enough for a first count ([`NearFaces::band_grid`]); the faces off the band are binned by
    /// [`NearFaces::update_fixed`] before anything searches them (a band with nothing to move,
    /// as a clean one, never needs them).
    pub(super) fn update_band(&mut self, mesh: &TriMesh, band: Range<usize>, scale: f64) {
        let cell = 2.0 * scale;
        let all = crate::geom::bounding_box(&mesh.positions).unwrap_or((DVec3::ZERO, DVec3::ZERO));
        let band_faces: Vec<u32> = band.clone().map(|f| f as u32).collect();
        self.band = Some(TriangleGrid::over_region(mesh, &band_faces, all, cell));
        self.region = band_region(mesh, band, cell);
    }

    /// The other half of [`NearFaces::update`], on the mesh as it was binned by
    /// [`NearFaces::update_band`]: the faces off the band binned again only when the band's
    /// region left the region they were binned for or the mesh's box changed.
    pub(super) fn update_fixed(&mut self, mesh: &TriMesh, band: Range<usize>, scale: f64) {
        let cell = 2.0 * scale;
        let all = crate::geom::bounding_box(&mesh.positions).unwrap_or((DVec3::ZERO, DVec3::ZERO));
        let region = self.region;
        let within =
            |r: (DVec3, DVec3), c: (DVec3, DVec3)| r.0.cmpge(c.0).all() && r.1.cmple(c.1).all();
        let reuse = self
            .fixed
            .as_ref()
            .is_some_and(|f| f.all == all && within(region, f.covered));
        if !reuse {
            // Two band edges of slack: later rounds move band vertices by about an edge.
            let covered = band_region(mesh, band.clone(), 2.0 * cell);
            let faces: Vec<u32> = (0..mesh.triangles.len())
                .filter(|g| !band.contains(g) && overlap(bbox(mesh, *g), covered))
                .map(|g| g as u32)
                .collect();
            self.fixed = Some(Fixed {
                grid: TriangleGrid::over_region(mesh, &faces, all, cell),
                all,
                covered,
            });
        }
    }

    /// This round's band faces, binned (after [`NearFaces::update`]).
    pub(super) fn band_grid(&self) -> Option<&TriangleGrid> {
        self.band.as_ref()
    }

    /// The faces off the band binned for the recount: every one whose box meets the region
    /// covered, which holds this round's band (after [`NearFaces::update`]).
    pub(super) fn recount(&self) -> Option<Recount<'_>> {
        self.fixed.as_ref().map(|f| Recount {
            region: f.covered,
            others: &f.grid,
        })
    }

    /// The near faces sharing a cell with the box `[lo, hi]`, sorted and unique (a superset of
    /// the near faces whose boxes overlap it). Empty before [`NearFaces::update`].
    pub(super) fn faces_in_box(&self, mesh: &TriMesh, lo: DVec3, hi: DVec3) -> Vec<u32> {
        let mut out = Vec::new();
        if let Some(fixed) = &self.fixed {
            fixed.grid.for_each_in_box(lo, hi, |g| {
                if overlap(bbox(mesh, g as usize), self.region) {
                    out.push(g);
                }
            });
        }
        if let Some(grid) = &self.band {
            grid.for_each_in_box(lo, hi, |f| out.push(f));
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::rng::Rng;

    /// A random soup: faces 0..300 around, 300..400 the band. Over rounds of band moves (small
    /// ones that keep the binned faces, and a large one that bins them anew) every query gives
    /// what one grid over that round's near faces gives.
    #[test]
    fn queries_equal_one_grid_over_the_near_faces() {
        let mut rng = Rng::new(21);
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for f in 0..400u32 {
            let c = if f < 300 {
                DVec3::new(
                    rng.range(-4.0, 4.0),
                    rng.range(-4.0, 4.0),
                    rng.range(-4.0, 4.0),
                )
            } else {
                DVec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-0.5, 0.5),
                )
            };
            for _ in 0..3 {
                positions.push(c + 0.2 * rng.unit_vector());
            }
            triangles.push([3 * f, 3 * f + 1, 3 * f + 2]);
        }
        let mut mesh = TriMesh::new(positions, triangles);
        let band = 300..400;
        let scale = 0.15;
        let mut near = NearFaces::default();
        for round in 0..4 {
            if round > 0 {
                let step = if round == 2 { 3.0 } else { 0.05 };
                for v in 900..1200 {
                    mesh.positions[v] += step * rng.unit_vector();
                }
            }
            near.update(&mesh, band.clone(), scale);
            let region = band_region(&mesh, band.clone(), 2.0 * scale);
            let faces: Vec<u32> = (0..400u32)
                .filter(|&g| overlap(bbox(&mesh, g as usize), region))
                .collect();
            let grid = TriangleGrid::over(&mesh, &faces, 2.0 * scale);
            for _ in 0..200 {
                let c = DVec3::new(
                    rng.range(-3.0, 3.0),
                    rng.range(-3.0, 3.0),
                    rng.range(-3.0, 3.0),
                );
                let h = DVec3::splat(rng.range(0.0, 0.6));
                let got = near.faces_in_box(&mesh, c - h, c + h);
                assert_eq!(got, grid.faces_in_box(c - h, c + h), "round {round} at {c}");
            }
        }
    }
}
