//! One jaw's teeth mask cropped from a label volume: its occupancy, its surface (points on the
//! mask's 0.5 level with outward normals) and the distance of each inside voxel to the
//! background.

use crate::volume::LabelVolume;
use glam::{DMat3, DMat4, DVec3};

/// A binary mask in a padded box of a label volume.
#[derive(Clone, Debug)]
pub(crate) struct JawMask {
    /// Voxels of the box along i, j, k.
    pub dims: [usize; 3],
    /// Index in the volume of the box's voxel (0, 0, 0) (may be one below the volume: padding).
    pub lo: [i64; 3],
    /// Box voxel index → world millimetres.
    pub to_world: DMat4,
    /// True for voxels of the mask; the box's outer layer is always false.
    pub inside: Vec<bool>,
}

/// The six face neighbours as index steps.
pub(crate) const FACES: [[i64; 3]; 6] = [
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
];

impl JawMask {
    /// The voxels of `vol` labelled `label`, in their bounding box padded by one voxel; `None`
    /// when the label is absent.
    pub fn from_volume(vol: &LabelVolume, label: u16) -> Option<JawMask> {
        let (blo, bhi) = *vol.label_boxes().get(&label)?;
        let lo: [i64; 3] = std::array::from_fn(|a| blo[a] as i64 - 1);
        let dims: [usize; 3] = std::array::from_fn(|a| bhi[a] - blo[a] + 3);
        let mut inside = vec![false; dims[0] * dims[1] * dims[2]];
        for k in 1..dims[2] - 1 {
            for j in 1..dims[1] - 1 {
                let row = vol.idx(0, (j as i64 + lo[1]) as usize, (k as i64 + lo[2]) as usize);
                for i in 1..dims[0] - 1 {
                    let vi = (i as i64 + lo[0]) as usize;
                    inside[i + dims[0] * (j + dims[1] * k)] = vol.labels[row + vi] == label;
                }
            }
        }
        let shift = DMat4::from_translation(DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64));
        Some(JawMask {
            dims,
            lo,
            to_world: vol.voxel_to_world * shift,
            inside,
        })
    }

    /// Linear index of box voxel (i, j, k).
    #[cfg(test)]
    pub fn idx(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Box voxel (i, j, k) of a linear index.
    #[inline]
    pub fn ijk(&self, id: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [id % nx, (id / nx) % ny, id / (nx * ny)]
    }

    /// The linear index of the face neighbour of `id` along `step` (the box's outer layer is
    /// never inside, so callers only step from inside voxels and stay in the box).
    #[inline]
    pub fn step(&self, id: usize, step: [i64; 3]) -> usize {
        let s = step[0] + self.dims[0] as i64 * (step[1] + self.dims[1] as i64 * step[2]);
        (id as i64 + s) as usize
    }

    /// World position of a box voxel centre.
    pub fn world(&self, id: usize) -> DVec3 {
        let [i, j, k] = self.ijk(id);
        self.to_world
            .transform_point3(DVec3::new(i as f64, j as f64, k as f64))
    }

    /// Voxel size along i, j, k (mm).
    pub fn spacing(&self) -> [f64; 3] {
        let m = DMat3::from_mat4(self.to_world);
        [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()]
    }

    /// Number of inside voxels.
    #[cfg(test)]
    pub fn count(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }

    /// Points on the mask's 0.5 level (the centre of every face between an inside and an
    /// outside voxel) with the outward unit normal of the inside voxel there (the gradient of
    /// the occupancy over its 3×3×3 neighbourhood, in world coordinates), in voxel order.
    pub fn surface_points(&self) -> (Vec<DVec3>, Vec<DVec3>) {
        let lin = DMat3::from_mat4(self.to_world);
        let normal_map = lin.inverse().transpose();
        let mut pts = Vec::new();
        let mut normals = Vec::new();
        for id in 0..self.inside.len() {
            if !self.inside[id] {
                continue;
            }
            let out: Vec<[i64; 3]> = FACES
                .iter()
                .copied()
                .filter(|&f| !self.inside[self.step(id, f)])
                .collect();
            if out.is_empty() {
                continue;
            }
            let n = (normal_map * self.outward_gradient(id)).normalize_or_zero();
            let c = self.world(id);
            for f in out {
                let d = DVec3::new(f[0] as f64, f[1] as f64, f[2] as f64);
                let n = if n == DVec3::ZERO {
                    (normal_map * d).normalize()
                } else {
                    n
                };
                pts.push(c + lin * (0.5 * d));
                normals.push(n);
            }
        }
        (pts, normals)
    }

    /// Σ over the 26 neighbours of (outside − inside)·offset, in voxel index space.
    fn outward_gradient(&self, id: usize) -> DVec3 {
        let mut g = DVec3::ZERO;
        for dk in -1..=1i64 {
            for dj in -1..=1i64 {
                for di in -1..=1i64 {
                    if !self.inside[self.step(id, [di, dj, dk])] {
                        g += DVec3::new(di as f64, dj as f64, dk as f64);
                    }
                }
            }
        }
        g
    }

    /// For every voxel, the distance (mm) from its centre to the nearest outside voxel centre
    /// (0 outside): an exact Euclidean distance transform, separable along the axes, with the
    /// voxel sizes of the axes.
    pub fn distance_mm(&self) -> Vec<f32> {
        let big = 1e18;
        let mut d2: Vec<f64> = self
            .inside
            .iter()
            .map(|&b| if b { big } else { 0.0 })
            .collect();
        let sp = self.spacing();
        let strides = [1, self.dims[0], self.dims[0] * self.dims[1]];
        let mut line = Vec::new();
        let mut out = Vec::new();
        for a in 0..3 {
            let n = self.dims[a];
            let s = strides[a];
            for start in 0..d2.len() {
                if (start / s) % n != 0 {
                    continue;
                }
                line.clear();
                line.extend((0..n).map(|x| d2[start + x * s]));
                edt_1d(&line, sp[a], &mut out);
                for (x, &v) in out.iter().enumerate() {
                    d2[start + x * s] = v;
                }
            }
        }
        d2.iter().map(|&v| v.sqrt() as f32).collect()
    }
}

/// The 1-D squared distance transform of sampled function `f` at spacing `h` (Felzenszwalb
/// and Huttenlocher's lower envelope of parabolas): `out[q] = min_p (h·(q − p))² + f[p]`.
fn edt_1d(f: &[f64], h: f64, out: &mut Vec<f64>) {
    let n = f.len();
    out.clear();
    out.resize(n, 0.0);
    let h2 = h * h;
    let mut v = vec![0usize; n];
    let mut z = vec![0f64; n + 1];
    let mut k = 0usize;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let inter = |p: usize, q: usize| -> f64 {
        let (pf, qf) = (p as f64, q as f64);
        ((f[q] / h2 + qf * qf) - (f[p] / h2 + pf * pf)) / (2.0 * (qf - pf))
    };
    for q in 1..n {
        let mut s = inter(v[k], q);
        while s <= z[k] {
            k -= 1;
            s = inter(v[k], q);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let d = q as f64 - v[k] as f64;
        *o = h2 * d * d + f[v[k]];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Frame;

    #[test]
    fn distance_transform_is_exact_on_a_slab() {
        // A slab 7 voxels thick along k (0.5 mm voxels): distances 0.5, 1.0, ... to the middle.
        let dims = [21, 21, 11];
        let mut labels = vec![0u16; 21 * 21 * 11];
        for k in 2..9 {
            for j in 0..21 {
                for i in 0..21 {
                    labels[i + 21 * (j + 21 * k)] = 4;
                }
            }
        }
        let v = LabelVolume::with_spacing(dims, [0.3, 0.3, 0.5], [0.0; 3], Frame::Lps, labels)
            .unwrap();
        let m = JawMask::from_volume(&v, 4).unwrap();
        assert_eq!(m.count(), 21 * 21 * 7);
        let d = m.distance_mm();
        // The box is the slab's box padded by one voxel: the slab is k = 1..=7 in the box.
        assert_eq!(m.dims, [23, 23, 9]);
        let at = |k: usize| d[m.idx(11, 11, k)];
        assert_eq!(at(0), 0.0);
        assert!((at(1) - 0.5).abs() < 1e-6 && (at(4) - 2.0).abs() < 1e-6);
        // Along i the box is padded: the nearest outside voxel is the padding, 0.3 mm away.
        assert!((d[m.idx(1, 11, 4)] - 0.3).abs() < 1e-6);
        let (p, n) = m.surface_points();
        assert_eq!(p.len(), n.len());
        // Every surface point is half a voxel outside an inside voxel centre, normals unit.
        assert!(n.iter().all(|n| (n.length() - 1.0).abs() < 1e-9));
    }
}
