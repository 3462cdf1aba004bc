//! IOS simulation: the visible surface of the drifted crowns and the gingiva, meshed as one
//! surface by surface nets at the scanner's resolution (vertices then spread evenly on the surface,
//! see [`super::relax`]), cropped to an open jaw, labeled per
//! vertex (FDI, 0 = gingiva) with label bleed along the margin, interproximal notches where the
//! scanner misses the contacts, optional small holes, and measurement noise; crowns that still
//! cross themselves after the noise lose the faces at fault to the gingiva
//! ([`super::crown_clean`]).

use super::crown_clean::untangle_crowns;
use super::crown_topology::make_crowns_disks;
use super::gingiva::{Gingiva, MarginPolar};
use super::grid::Grid;
use super::layout::PlacedTooth;
use super::project::project;
use super::relax::{FoldGuard, relax_on_surface};
use super::rng::Rng;
use super::rough::{IosRoughness, roughen};
use super::surface_nets::{largest_component, surface_nets_split};
use crate::mesh::TriMesh;
use glam::{DVec2, DVec3};

/// How the IOS departs from a perfect scan.
#[derive(Clone, Debug, PartialEq)]
pub struct IosRealism {
    /// Grid spacing of the scan surface (≈ vertex spacing, mm).
    pub spacing: f64,
    /// Standard deviation of the vertex noise (mm; clamped at 2.5 sigma).
    pub noise: f64,
    /// Amplitude of the tooth/gingiva label bleed along the margin (mm).
    pub label_bleed: f64,
    /// Cut interproximal notches where neighbouring crowns touch.
    pub notches: bool,
    /// Number of small holes punched into random crowns (0 = none).
    pub holes: usize,
    /// A rough export instead of the clean scan (`None`: clean; see [`super::IosExport::roughness`]).
    pub rough: Option<IosRoughness>,
}

impl Default for IosRealism {
    fn default() -> Self {
        Self {
            spacing: 0.18,
            noise: 0.01,
            label_bleed: 0.25,
            notches: true,
            holes: 0,
            rough: None,
        }
    }
}

/// A tooth as the IOS sees it: moved by its drift (drifted world frame).
pub struct IosTooth {
    /// The tooth moved by its drift.
    pub tooth: PlacedTooth,
    /// FDI label.
    pub fdi: u8,
    /// Bleed wave (amplitude, phase 1, phase 2, offset).
    pub bleed: (f64, f64, f64, f64),
}

/// A contact between two IOS teeth (drifted world): where a notch goes.
pub struct Contact {
    /// Contact point.
    pub point: DVec3,
}

struct Field<'a> {
    teeth: &'a [IosTooth],
    boxes: Vec<(DVec3, DVec3)>,
    gum: &'a Gingiva,
}

impl Field<'_> {
    /// (gingiva value, best tooth index, its value).
    fn parts(&self, p: DVec3) -> (f64, Option<usize>, f64) {
        let g = self.gum.eval(p);
        let mut best = (None, f64::INFINITY);
        for (i, (lo, hi)) in self.boxes.iter().enumerate() {
            let d = (*lo - p).max(p - *hi).max(DVec3::ZERO);
            let v = if d == DVec3::ZERO {
                self.teeth[i].tooth.eval(p)
            } else {
                d.length() + 0.01
            };
            if v < best.1 {
                best = (Some(i), v);
            }
        }
        (g, best.0, best.1)
    }

    /// The teeth whose bounding box is within `pad` of `p`.
    fn teeth_near(&self, p: DVec3, pad: f64) -> Vec<usize> {
        (0..self.boxes.len())
            .filter(|&i| {
                let (lo, hi) = self.boxes[i];
                (lo - p).max(p - hi).max(DVec3::ZERO).length() <= pad
            })
            .collect()
    }

    /// The field near `p` where only the teeth `near` can be close (see [`Field::teeth_near`]).
    fn eval_among(&self, p: DVec3, near: &[usize]) -> f64 {
        near.iter()
            .map(|&i| self.teeth[i].tooth.eval(p))
            .fold(self.gum.eval(p), f64::min)
    }

    fn eval(&self, p: DVec3) -> f64 {
        // Deep under the gum the union is negative whatever the teeth do: no need to look.
        let g = self.gum.eval(p);
        if g < -1.0 {
            return g;
        }
        let (g, _, t) = self.parts(p);
        g.min(t)
    }
}

/// Simulates the IOS jaw in the drifted world frame: mesh, per-vertex labels, and per tooth
/// the true margin where the simulated gingiva meets it (drifted world frame).
pub fn simulate(
    teeth: &[IosTooth],
    contacts: &[Contact],
    occ: DVec3,
    realism: &IosRealism,
    rng: &mut Rng,
) -> (TriMesh, Vec<i32>, Vec<Vec<DVec3>>) {
    let (gum, glo, ghi) = gingiva_and_extent(teeth, occ);
    let boxes: Vec<(DVec3, DVec3)> = teeth.iter().map(|t| t.tooth.world_box()).collect();
    let field = Field {
        teeth,
        boxes,
        gum: &gum,
    };
    let rough = realism.rough.as_ref();
    let h = match rough {
        Some(r) => realism.spacing / r.density.max(1e-3).sqrt(),
        None => realism.spacing,
    };
    let mut grid = Grid::covering(glo, ghi, h, 1);
    grid.fill(16, 2.0, |p| field.eval(p));
    grid.make_well_composed();
    // A rough export keeps marching-cubes-like slivers.
    let raw = surface_nets_split(&grid, rough.is_some());
    let cropped = cropped(&raw, &grid, h, contacts, &gum, occ, realism.notches, rng);
    let mut mesh = largest_component(&cropped);
    let guard = FoldGuard::new(&mesh);
    if rough.is_none() {
        relax(&mut mesh, &guard, &field, h);
    }
    let (mut labels, mut level) = label(&mut mesh, &field, teeth, &guard, rough.is_some(), h);
    if let Some(r) = rough {
        let fdis: Vec<u8> = teeth.iter().map(|t| t.fdi).collect();
        if realism.holes > 0 {
            punch_holes(&mut mesh, &mut labels, Some(&mut level), realism.holes, rng);
        }
        roughen(&mut mesh, &mut labels, level, &fdis, occ, h, r, rng);
        let margins = true_margins(teeth, &gum);
        return (mesh, labels, margins);
    }
    // Small holes in random crowns.
    if realism.holes > 0 {
        punch_holes(&mut mesh, &mut labels, None, realism.holes, rng);
    }
    // Measurement noise.
    if realism.noise > 0.0 {
        for p in &mut mesh.positions {
            *p += DVec3::new(
                rng.normal_clamped(2.5),
                rng.normal_clamped(2.5),
                rng.normal_clamped(2.5),
            ) * realism.noise;
        }
    }
    make_crowns_disks(&mesh, &mut labels, realism.holes > 0);
    untangle_crowns(&mesh, &mut labels, realism.holes > 0, 6);
    let margins = true_margins(teeth, &gum);
    (mesh, labels, margins)
}

/// The gingiva height field from the drifted margins, and the grid's extent: the teeth's
/// margins and crown tops, padded, from under the lowest margin to above the highest crown.
fn gingiva_and_extent(teeth: &[IosTooth], occ: DVec3) -> (Gingiva, DVec3, DVec3) {
    let polars: Vec<MarginPolar> = teeth
        .iter()
        .map(|t| MarginPolar::new(&t.tooth.margin(144), occ, t.tooth.rot * DVec3::X))
        .collect();
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut min_margin = f64::INFINITY;
    for t in teeth {
        for p in t.tooth.margin(36) {
            lo = lo.min(p);
            hi = hi.max(p);
            min_margin = min_margin.min(p.dot(occ));
        }
        let top = t
            .tooth
            .to_world(DVec3::new(0.0, 0.0, t.tooth.shape.crown_height + 0.3));
        lo = lo.min(top);
        hi = hi.max(top);
    }
    let reach = 5.0;
    let gum = Gingiva::new(
        &polars,
        DVec2::new(lo.x - reach - 1.0, lo.y - reach - 1.0),
        DVec2::new(hi.x + reach + 1.0, hi.y + reach + 1.0),
        0.25,
        occ,
        min_margin - 30.0,
    );
    let bottom = min_margin - 4.0;
    // Occlusal extent: from `bottom` to the highest crown point.
    let (zlo, zhi) = if occ.z > 0.0 {
        (bottom, hi.z + 0.8)
    } else {
        (lo.z - 0.8, -bottom)
    };
    let glo = DVec3::new(lo.x - reach, lo.y - reach, zlo);
    let ghi = DVec3::new(hi.x + reach, hi.y + reach, zhi);
    (gum, glo, ghi)
}

/// The surface-nets mesh `raw` of `grid` cropped: faces touching the grid's outer shell (the
/// artificial closure) dropped, and with `notches` the faces near each interproximal contact
/// (the scanner cannot see into the contacts).
#[allow(clippy::too_many_arguments)]
fn cropped(
    raw: &TriMesh,
    grid: &Grid,
    h: f64,
    contacts: &[Contact],
    gum: &Gingiva,
    occ: DVec3,
    notches: bool,
    rng: &mut Rng,
) -> TriMesh {
    // Crop: drop faces touching the grid's outer shell (the artificial closure).
    let (blo, bhi) = (
        grid.origin + DVec3::splat(1.5 * h),
        grid.origin
            + DVec3::new(
                grid.dims[0] as f64 - 2.5,
                grid.dims[1] as f64 - 2.5,
                grid.dims[2] as f64 - 2.5,
            ) * h,
    );
    let inside = |p: DVec3| p.cmpgt(blo).all() && p.cmplt(bhi).all();
    let mut keep: Vec<bool> = raw
        .triangles
        .iter()
        .map(|t| t.iter().all(|&v| inside(raw.positions[v as usize])))
        .collect();
    // Interproximal notches: the scanner cannot see into the contacts.
    if notches {
        for c in contacts {
            let r = rng.range(0.55, 0.9);
            let top = c.point + occ * 0.6;
            let floor = gum.height(DVec2::new(c.point.x, c.point.y)) - 0.8;
            let depth = (c.point.dot(occ) - floor).max(1.0);
            let bot = c.point - occ * depth;
            for (k, t) in raw.triangles.iter().enumerate() {
                if keep[k]
                    && t.iter()
                        .any(|&v| seg_dist(raw.positions[v as usize], bot, top) < r)
                {
                    keep[k] = false;
                }
            }
        }
    }
    TriMesh::new(
        raw.positions.clone(),
        raw.triangles
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(t, _)| *t)
            .collect(),
    )
}

/// Per vertex its label (the nearest tooth where the tooth is under the gingiva plus the label
/// bleed, else 0) and, for a `rough` export, the labelling level (negative on the tooth side of
/// the label boundary, used to clip the export through it); crown vertices projected onto their
/// tooth (through the fold guard on a clean scan).
fn label(
    mesh: &mut TriMesh,
    field: &Field<'_>,
    teeth: &[IosTooth],
    guard: &FoldGuard,
    rough: bool,
    h: f64,
) -> (Vec<i32>, Vec<f64>) {
    let mut labels = vec![0i32; mesh.positions.len()];
    let mut level = vec![0.0f64; if rough { labels.len() } else { 0 }];
    for (v, label) in labels.iter_mut().enumerate() {
        let p = mesh.positions[v];
        let (g, best, tv) = field.parts(p);
        let Some(i) = best else { continue };
        let t = &teeth[i];
        let l = t.tooth.to_local(p);
        let phi = l.y.atan2(l.x);
        let (amp, a, b, off) = t.bleed;
        let bleed = amp * (0.6 * (2.0 * phi + a).sin() + 0.4 * (5.0 * phi + b).sin()) + off;
        if tv <= g + bleed && tv < 1.0 {
            *label = t.fdi as i32;
        }
        if rough {
            level[v] = if tv < 1.0 { tv - (g + bleed) } else { 1.0 };
        }
        if tv < g {
            let q = project(p, &|q| t.tooth.eval(q), h);
            if rough {
                mesh.positions[v] = q; // raw: no guard against folds
            } else {
                guard.try_move(mesh, v, q);
            }
        }
    }
    (labels, level)
}

/// Where the gingiva meets each tooth (120 points per tooth), the teeth in parallel.
fn true_margins(teeth: &[IosTooth], gum: &Gingiva) -> Vec<Vec<DVec3>> {
    crate::par::map_ordered(teeth, |t| t.tooth.margin_against(120, &|p| gum.eval(p)))
}

/// A scanner spreads its vertices evenly: no surface-nets slivers. Relaxes the vertices near
/// the teeth (the gingiva further away never becomes crown) on the field's surface.
fn relax(mesh: &mut TriMesh, guard: &FoldGuard, field: &Field<'_>, h: f64) {
    // The teeth near each vertex, in parallel over blocks of vertices (a pure function of each).
    let blocks: Vec<&[DVec3]> = mesh.positions.chunks(4096).collect();
    let near: Vec<Vec<usize>> = crate::par::map_ordered(&blocks, |b| {
        b.iter()
            .map(|&p| field.teeth_near(p, 2.0 * h))
            .collect::<Vec<_>>()
    })
    .concat();
    let movable: Vec<bool> = near.iter().map(|n| !n.is_empty()).collect();
    relax_on_surface(
        mesh,
        guard,
        &|v, p| field.eval_among(p, &near[v]),
        &movable,
        0.5 * h,
        2,
    );
}

/// Punches `holes` small holes (0.25–0.5 mm radius) into random crowns and drops the vertices
/// left unused, carrying the labels (and `level`, when given) along.
fn punch_holes(
    mesh: &mut TriMesh,
    labels: &mut Vec<i32>,
    level: Option<&mut Vec<f64>>,
    holes: usize,
    rng: &mut Rng,
) {
    let crown_vertices: Vec<usize> = (0..labels.len()).filter(|&v| labels[v] != 0).collect();
    let mut tris = mesh.triangles.clone();
    for _ in 0..holes {
        if crown_vertices.is_empty() {
            break;
        }
        let c = mesh.positions[crown_vertices[rng.below(crown_vertices.len())]];
        let r = rng.range(0.25, 0.5);
        tris.retain(|t| {
            t.iter()
                .all(|&v| (mesh.positions[v as usize] - c).length() > r)
        });
    }
    mesh.triangles = tris;
    let map = mesh.compact();
    let mut nl = vec![0; mesh.positions.len()];
    let mut nv = vec![0.0; if level.is_some() { nl.len() } else { 0 }];
    for (old, &new) in map.iter().enumerate() {
        if new != u32::MAX {
            nl[new as usize] = labels[old];
            if let Some(l) = &level {
                nv[new as usize] = l[old];
            }
        }
    }
    *labels = nl;
    if let Some(l) = level {
        *l = nv;
    }
}

fn seg_dist(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).length()
}
