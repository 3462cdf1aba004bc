//! Unit sanity checks: catch meshes in metres (or micrometres) instead of millimetres, and two
//! modalities at wildly different scales, before registration produces nonsense.
//!
//! Tooth sizes (millimetres): a whole permanent molar is about 10 × 11 × 20 mm (diagonal
//! ~25 mm), an incisor crown about 9 × 7 × 10 mm (diagonal ~15 mm), a primary incisor crown
//! ~5 mm. The plausible range below leaves a wide margin on both sides; a factor 1000 off
//! (metres, micrometres) or 10 (centimetres) cannot hide in it.

use crate::geom::bounding_box;
use crate::mesh::TriMesh;
use crate::{Error, Result};
use glam::DVec3;

/// Smallest plausible bounding-box diagonal of a tooth or crown, in mm.
pub const TOOTH_DIAGONAL_MIN_MM: f64 = 2.0;
/// Largest plausible bounding-box diagonal of a tooth or crown, in mm.
pub const TOOTH_DIAGONAL_MAX_MM: f64 = 60.0;
/// Smallest accepted ratio of median tooth widths CBCT / IOS.
pub const SCALE_RATIO_MIN: f64 = 0.5;
/// Largest accepted ratio of median tooth widths CBCT / IOS.
pub const SCALE_RATIO_MAX: f64 = 2.0;

/// The bounding-box diagonal of a mesh's vertices (`None` when it has none).
pub fn bbox_diagonal(mesh: &TriMesh) -> Option<f64> {
    bounding_box(&mesh.positions).map(|(lo, hi)| (hi - lo).length())
}

/// Checks that a tooth or crown has a plausible size in millimetres; the error (a
/// [`Error::UnitMismatch`] for tooth `fdi`) names the modality, the measured diagonal and the
/// likely unit.
pub fn check_tooth_scale(mesh: &TriMesh, fdi: u8, modality_name: &str) -> Result<()> {
    let d = bbox_diagonal(mesh).ok_or_else(|| {
        Error::InvalidArgument(format!("{modality_name} mesh has no vertices")).in_tooth(fdi)
    })?;
    if !d.is_finite() {
        return Err(Error::InvalidArgument(format!(
            "{modality_name} mesh has a non-finite coordinate"
        ))
        .in_tooth(fdi));
    }
    let ok = |x: f64| (TOOTH_DIAGONAL_MIN_MM..=TOOTH_DIAGONAL_MAX_MM).contains(&x);
    if ok(d) {
        return Ok(());
    }
    let range = format!("{TOOTH_DIAGONAL_MIN_MM}-{TOOTH_DIAGONAL_MAX_MM} mm");
    let msg = if d < TOOTH_DIAGONAL_MIN_MM {
        if ok(d * 1000.0) {
            format!(
                "{modality_name} tooth looks like metres (bounding-box diagonal {d:.4}, a tooth is {range}): convert to millimetres (x1000)"
            )
        } else if ok(d * 10.0) {
            format!(
                "{modality_name} tooth looks like centimetres (bounding-box diagonal {d:.3}, a tooth is {range}): convert to millimetres (x10)"
            )
        } else {
            format!(
                "{modality_name} tooth is far too small (bounding-box diagonal {d:.3e}, a tooth is {range} in millimetres)"
            )
        }
    } else if ok(d / 1000.0) {
        format!(
            "{modality_name} tooth looks like micrometres (bounding-box diagonal {d:.1}, a tooth is {range}): convert to millimetres (/1000)"
        )
    } else {
        format!(
            "{modality_name} tooth is far too large (bounding-box diagonal {d:.3e}, a tooth is {range} in millimetres): wrong units or not a single tooth?"
        )
    };
    Err(Error::UnitMismatch(msg).in_tooth(fdi))
}

/// A tooth width comparable between an IOS crown and a whole CBCT tooth: the middle of the
/// three principal extents of the vertices (the long axis, which the crown lacks, is the
/// largest extent of a whole tooth; the crown's height is its smallest). `None` without
/// vertices.
pub fn tooth_width(mesh: &TriMesh) -> Option<f64> {
    let n = mesh.positions.len();
    if n == 0 {
        return None;
    }
    let c = mesh.positions.iter().copied().sum::<DVec3>() / n as f64;
    let mut cov = nalgebra::Matrix3::<f64>::zeros();
    for p in &mesh.positions {
        let d = nalgebra::Vector3::new(p.x - c.x, p.y - c.y, p.z - c.z);
        cov += d * d.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(cov);
    let mut ext: Vec<f64> = (0..3)
        .map(|k| {
            let axis = eig.eigenvectors.column(k);
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for p in &mesh.positions {
                let t = axis[0] * p.x + axis[1] * p.y + axis[2] * p.z;
                lo = lo.min(t);
                hi = hi.max(t);
            }
            hi - lo
        })
        .collect();
    ext.sort_by(f64::total_cmp);
    Some(ext[1])
}

/// The median of finite values (`None` when there are none).
pub fn median(values: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    })
}

/// Compares the median tooth sizes of two modalities (e.g. [`tooth_width`] per tooth): a
/// ratio CBCT / IOS outside [[`SCALE_RATIO_MIN`], [`SCALE_RATIO_MAX`]] is an
/// [`Error::UnitMismatch`] naming both medians. Passes when either list is empty (nothing to
/// compare).
pub fn check_consistent_scales(ios_sizes: &[f64], cbct_sizes: &[f64]) -> Result<()> {
    let (Some(ios), Some(cbct)) = (median(ios_sizes), median(cbct_sizes)) else {
        return Ok(());
    };
    if ios <= 0.0 || cbct <= 0.0 {
        return Err(Error::UnitMismatch(format!(
            "median tooth size is not positive (IOS {ios}, CBCT {cbct})"
        )));
    }
    let r = cbct / ios;
    if !(SCALE_RATIO_MIN..=SCALE_RATIO_MAX).contains(&r) {
        return Err(Error::UnitMismatch(format!(
            "IOS and CBCT teeth differ in scale: median IOS tooth size {ios:.4}, median CBCT tooth size {cbct:.4} (ratio {r:.3}, expected {SCALE_RATIO_MIN}-{SCALE_RATIO_MAX}); are both in millimetres?"
        )));
    }
    Ok(())
}

/// Plausible median bounding-box diagonal (mm) of the IOS crowns of a jaw: an incisor crown of a
/// primary tooth or a teeth-only patch is ~4 mm, a molar crown ~14 mm.
pub const IOS_MEDIAN_DIAGONAL_MM: (f64, f64) = (3.0, 40.0);
/// Plausible median bounding-box diagonal (mm) of the CBCT teeth of a jaw: a primary incisor is
/// ~15 mm, a permanent molar ~25 mm (crown-only CBCT segmentations ~10 mm).
pub const CBCT_MEDIAN_DIAGONAL_MM: (f64, f64) = (6.0, 80.0);
/// Bounds (mm) of a single tooth's bounding-box diagonal outside which it is refused on entry:
/// only what no unit in millimetres can give (a tooth in metres is ~0.005-0.03, in micrometres
/// ~4000-30000). The range between is judged at registration over all teeth
/// ([`check_jaw_scales`]).
pub const ENTRY_DIAGONAL_MM: (f64, f64) = (0.5, 250.0);

/// The likely unit of a length `d` that should lie in `range` millimetres: "metres (x1000)",
/// "centimetres (x10)", "micrometres (/1000)", or `None` when no such factor brings it in.
fn likely_unit(d: f64, range: (f64, f64)) -> Option<&'static str> {
    let ok = |x: f64| (range.0..=range.1).contains(&x);
    [
        (1000.0, "metres: convert to millimetres (x1000)"),
        (10.0, "centimetres: convert to millimetres (x10)"),
        (0.001, "micrometres: convert to millimetres (/1000)"),
    ]
    .into_iter()
    .find(|&(f, _)| ok(d * f))
    .map(|(_, u)| u)
}

fn scale_message(modality: &str, what: &str, d: f64, range: (f64, f64)) -> String {
    let unit = likely_unit(d, range).map_or_else(
        || "far from any tooth size in millimetres".to_string(),
        |u| format!("looks like {u}"),
    );
    format!(
        "{modality} {what} {d:.4} is outside the plausible {}-{} mm: {modality} {unit}",
        range.0, range.1
    )
}

/// The entry check of one tooth of `modality` (an [`Error::UnitMismatch`] naming the modality and
/// the likely unit when its bounding-box diagonal is outside [`ENTRY_DIAGONAL_MM`]).
pub fn check_entry_scale(mesh: &TriMesh, modality: &str) -> Result<()> {
    match bbox_diagonal(mesh) {
        Some(d) if d.is_finite() && !(ENTRY_DIAGONAL_MM.0..=ENTRY_DIAGONAL_MM.1).contains(&d) => {
            Err(Error::UnitMismatch(scale_message(
                modality,
                "tooth bounding-box diagonal",
                d,
                if d < ENTRY_DIAGONAL_MM.0 {
                    CBCT_MEDIAN_DIAGONAL_MM
                } else {
                    (TOOTH_DIAGONAL_MIN_MM, TOOTH_DIAGONAL_MAX_MM)
                },
            )))
        }
        _ => Ok(()),
    }
}

/// The registration-time check over all teeth of both modalities: each modality's median
/// bounding-box diagonal in its plausible range ([`IOS_MEDIAN_DIAGONAL_MM`],
/// [`CBCT_MEDIAN_DIAGONAL_MM`]) and the two at the same scale ([`check_consistent_scales`] on
/// [`tooth_width`]). The [`Error::UnitMismatch`] names the modality and the likely unit. Passes
/// when a modality has no teeth.
pub fn check_jaw_scales(
    ios: &std::collections::BTreeMap<u8, TriMesh>,
    cbct: &std::collections::BTreeMap<u8, TriMesh>,
) -> Result<()> {
    let diag = |m: &std::collections::BTreeMap<u8, TriMesh>| {
        median(&m.values().filter_map(bbox_diagonal).collect::<Vec<_>>())
    };
    for (name, what, d, range) in [
        ("IOS", "median crown", diag(ios), IOS_MEDIAN_DIAGONAL_MM),
        ("CBCT", "median tooth", diag(cbct), CBCT_MEDIAN_DIAGONAL_MM),
    ] {
        if let Some(d) = d
            && !(range.0..=range.1).contains(&d)
        {
            return Err(Error::UnitMismatch(scale_message(
                name,
                &format!("{what} bounding-box diagonal"),
                d,
                range,
            )));
        }
    }
    let width = |m: &std::collections::BTreeMap<u8, TriMesh>| {
        m.values().filter_map(tooth_width).collect::<Vec<_>>()
    };
    check_consistent_scales(&width(ios), &width(cbct))
}
