//! Closed tooth meshes voxelized into a label volume (a CBCT segmentation with known truth):
//! a voxel belongs to a tooth when its centre lies inside the tooth's closed mesh, decided by
//! ray parity along the grid's k columns. The grid may be oblique (any rotation of its axes) and
//! every tooth may carry one class label (DentalSegmentator's per-jaw teeth classes) instead of
//! its FDI number. Deterministic: the same meshes and options give the same volume bit for bit.

use crate::mesh::TriMesh;
use crate::volume::{Frame, LabelVolume};
use crate::{Error, Result};
use glam::{DMat3, DMat4, DVec3};
use std::collections::BTreeMap;

/// How [`voxelize`] lays out the grid and labels the voxels.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelizeOptions {
    /// Voxel size (mm), the same along every axis.
    pub voxel_mm: f64,
    /// The grid's axes in the meshes' frame (columns of a rotation); identity for an
    /// axis-aligned grid.
    pub axes: DMat3,
    /// Margin (mm) of background around the teeth.
    pub pad_mm: f64,
    /// Label of every tooth voxel (e.g. 3 for DentalSegmentator's upper teeth); `None` labels a
    /// voxel with its tooth's FDI number.
    pub class: Option<u16>,
    /// Frame recorded in the volume (the meshes' frame).
    pub frame: Frame,
}

impl Default for VoxelizeOptions {
    fn default() -> Self {
        VoxelizeOptions {
            voxel_mm: 0.3,
            axes: DMat3::IDENTITY,
            pad_mm: 1.0,
            class: None,
            frame: Frame::Lps,
        }
    }
}

/// Voxelizes closed tooth meshes (by FDI). A voxel centre inside several teeth goes to the
/// smallest FDI. Errors name the cause: no teeth, a voxel size that is not positive, axes that
/// are not a rotation.
pub fn voxelize(teeth: &BTreeMap<u8, TriMesh>, opts: &VoxelizeOptions) -> Result<LabelVolume> {
    let h = opts.voxel_mm;
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "voxel size {h} mm: must be positive"
        )));
    }
    let r = opts.axes;
    let orthonormal = (r.transpose() * r - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .all(|v| v.abs() < 1e-9);
    if !orthonormal || r.determinant() < 0.0 {
        return Err(Error::InvalidArgument(
            "voxelize: the grid's axes must be a rotation".into(),
        ));
    }
    // Mesh vertices in grid coordinates (mm along the grid's axes).
    let to_grid = |p: DVec3| r.transpose() * p;
    let all: Vec<DVec3> = teeth
        .values()
        .flat_map(|m| m.positions.iter().map(|p| to_grid(*p)))
        .collect();
    let Some((lo, hi)) = crate::geom::bounding_box(&all) else {
        return Err(Error::MissingData("voxelize: no tooth vertices".into()));
    };
    // Voxel centres half a voxel off the teeth's bounding planes.
    let lo = lo - DVec3::splat(opts.pad_mm.max(0.0) + 0.5 * h);
    let dims: [usize; 3] =
        std::array::from_fn(|a| ((hi[a] - lo[a] + opts.pad_mm.max(0.0)) / h).ceil() as usize + 2);
    let n = dims[0] * dims[1] * dims[2];
    let mut labels = vec![0u16; n];
    for (&fdi, mesh) in teeth {
        let label = opts.class.unwrap_or(fdi as u16);
        // Vertices in continuous voxel index coordinates.
        let pos: Vec<DVec3> = mesh
            .positions
            .iter()
            .map(|p| (to_grid(*p) - lo) / h)
            .collect();
        let cols = column_crossings(&pos, &mesh.triangles, DVec3::ZERO, 1.0, dims);
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                inside_samples(&cols[i + dims[0] * j], 0.0, 1.0, dims[2], |k| {
                    let id = i + dims[0] * (j + dims[1] * k);
                    if labels[id] == 0 {
                        labels[id] = label;
                    }
                });
            }
        }
    }
    let m = DMat4::from_mat3_translation(r * h, r * lo);
    LabelVolume::new(dims, m, opts.frame, labels)
}

/// Per grid column (i, j), the sorted heights at which the line through
/// `origin + (i·h, j·h)` parallel to z crosses the triangles; the line is shifted by a tiny
/// irrational fraction of `h` so that it misses edges and vertices. `dims` gives the columns
/// (its third entry is not used).
pub(crate) fn column_crossings(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    origin: DVec3,
    h: f64,
    dims: [usize; 3],
) -> Vec<Vec<f64>> {
    let [nx, ny, _] = dims;
    let off = (
        h * 1e-4 * std::f64::consts::SQRT_2,
        h * 1e-4 * std::f64::consts::PI,
    );
    let mut hits: Vec<Vec<f64>> = vec![Vec::new(); nx * ny];
    for t in triangles {
        let [a, b, c] = [0, 1, 2].map(|k| positions[t[k] as usize]);
        let tlo = a.min(b).min(c);
        let thi = a.max(b).max(c);
        let first = |lo: f64, o: f64, sh: f64| ((lo - o - sh) / h).ceil().max(0.0) as usize;
        let end = |hi: f64, o: f64, sh: f64| (((hi - o - sh) / h).floor().max(-1.0) + 1.0) as usize;
        let (i0, i1) = (first(tlo.x, origin.x, off.0), end(thi.x, origin.x, off.0));
        let (j0, j1) = (first(tlo.y, origin.y, off.1), end(thi.y, origin.y, off.1));
        for j in j0..j1.min(ny) {
            for i in i0..i1.min(nx) {
                let x = origin.x + i as f64 * h + off.0;
                let y = origin.y + j as f64 * h + off.1;
                if let Some(z) = vertical_hit(x, y, a, b, c) {
                    hits[i + nx * j].push(z);
                }
            }
        }
    }
    for col in &mut hits {
        col.sort_by(|p, q| p.total_cmp(q));
    }
    hits
}

/// Calls `f(k)` for every sample `z0 + k·h` (k < `nz`) of a column that lies inside a closed
/// surface: an odd number of the column's sorted `crossings` below it.
pub(crate) fn inside_samples(
    crossings: &[f64],
    z0: f64,
    h: f64,
    nz: usize,
    mut f: impl FnMut(usize),
) {
    let mut below = 0;
    for k in 0..nz {
        let z = z0 + k as f64 * h;
        while below < crossings.len() && crossings[below] < z {
            below += 1;
        }
        if below % 2 == 1 {
            f(k);
        }
    }
}

/// Height at which the vertical line through (x, y) crosses triangle abc, if it does.
fn vertical_hit(x: f64, y: f64, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let d = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if d.abs() < 1e-18 {
        return None;
    }
    let u = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / d;
    let v = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / d;
    if u < 0.0 || v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(a.z + u * (b.z - a.z) + v * (c.z - a.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed axis-aligned box from `lo` to `hi`, outward faces.
    fn cuboid(lo: DVec3, hi: DVec3) -> TriMesh {
        let p = |i: usize| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        };
        let positions = (0..8).map(p).collect();
        let triangles = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        TriMesh::new(positions, triangles)
    }

    /// A closed UV sphere.
    fn sphere(c: DVec3, r: f64, n: usize) -> TriMesh {
        let mut positions = vec![c + DVec3::Z * r, c - DVec3::Z * r];
        for a in 1..n {
            let th = std::f64::consts::PI * a as f64 / n as f64;
            for b in 0..2 * n {
                let ph = std::f64::consts::PI * b as f64 / n as f64;
                let d = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                positions.push(c + d * r);
            }
        }
        let ring = |a: usize, b: usize| (2 + (a - 1) * 2 * n + b % (2 * n)) as u32;
        let mut triangles = Vec::new();
        for b in 0..2 * n {
            triangles.push([0, ring(1, b), ring(1, b + 1)]);
            triangles.push([1, ring(n - 1, b + 1), ring(n - 1, b)]);
            for a in 1..n - 1 {
                let (p, q, r2, s) = (
                    ring(a, b),
                    ring(a, b + 1),
                    ring(a + 1, b),
                    ring(a + 1, b + 1),
                );
                triangles.push([p, r2, s]);
                triangles.push([p, s, q]);
            }
        }
        TriMesh::new(positions, triangles)
    }

    fn oblique() -> DMat3 {
        DMat3::from_rotation_x(20f64.to_radians()) * DMat3::from_rotation_z(30f64.to_radians())
    }

    #[test]
    fn a_box_and_a_sphere_fill_their_volume() {
        let teeth = BTreeMap::from([
            (
                11u8,
                cuboid(DVec3::new(0.05, 0.05, 0.05), DVec3::new(4.05, 3.05, 6.05)),
            ),
            (21u8, sphere(DVec3::new(10.0, 2.0, 3.0), 3.0, 48)),
        ]);
        let sphere_vol = teeth[&21].signed_volume();
        for (axes, class) in [(DMat3::IDENTITY, None), (oblique(), Some(3))] {
            let opts = VoxelizeOptions {
                voxel_mm: 0.2,
                axes,
                class,
                ..Default::default()
            };
            let v = voxelize(&teeth, &opts).unwrap();
            let voxel = 0.2f64.powi(3);
            let counts = v.label_counts();
            let (box_n, sph_n) = match class {
                None => (counts[&11], counts[&21]),
                // One class: the two solids are apart, so split the count by position.
                Some(c) => {
                    assert_eq!(counts.keys().copied().collect::<Vec<_>>(), vec![c]);
                    let [nx, ny, _] = v.dims;
                    let mut n = (0, 0);
                    for (id, &l) in v.labels.iter().enumerate() {
                        let ijk = DVec3::new(
                            (id % nx) as f64,
                            ((id / nx) % ny) as f64,
                            (id / (nx * ny)) as f64,
                        );
                        if l == c && v.world(ijk).x < 7.0 {
                            n.0 += 1;
                        } else if l == c {
                            n.1 += 1;
                        }
                    }
                    n
                }
            };
            // 72 mm³ and the polyhedral sphere's volume, within a surface layer's error.
            let box_err = (box_n as f64 * voxel - 72.0).abs() / 72.0;
            let sph_err = (sph_n as f64 * voxel - sphere_vol).abs() / sphere_vol;
            assert!(box_err < 0.03, "box {box_n} voxels, {axes:?}");
            assert!(sph_err < 0.03, "sphere {sph_n} voxels vs {sphere_vol} mm³");
            // Voxel centres labelled inside lie inside (the box, exactly).
            let [nx, ny, _] = v.dims;
            for (id, &l) in v.labels.iter().enumerate() {
                let ijk = DVec3::new(
                    (id % nx) as f64,
                    ((id / nx) % ny) as f64,
                    (id / (nx * ny)) as f64,
                );
                let p = v.world(ijk);
                if l != 0 && p.x < 7.0 {
                    assert!(p.cmpge(DVec3::splat(0.04)).all(), "{p}");
                    assert!(p.cmple(DVec3::new(4.06, 3.06, 6.06)).all(), "{p}");
                }
                if l != 0 && p.x >= 7.0 {
                    assert!(p.distance(DVec3::new(10.0, 2.0, 3.0)) < 3.01, "{p}");
                }
            }
            assert_eq!(v, voxelize(&teeth, &opts).unwrap(), "deterministic");
        }
    }

    #[test]
    fn bad_options_are_named() {
        let teeth = BTreeMap::from([(11u8, cuboid(DVec3::ZERO, DVec3::ONE))]);
        let e = voxelize(
            &teeth,
            &VoxelizeOptions {
                voxel_mm: 0.0,
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("voxel size"), "{e}");
        let e = voxelize(
            &teeth,
            &VoxelizeOptions {
                axes: DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0)),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("rotation"), "{e}");
        assert!(voxelize(&BTreeMap::new(), &VoxelizeOptions::default()).is_err());
    }
}
