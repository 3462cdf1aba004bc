//! The shared real data (`../shared/data/real` or `TOOTHFUSE_REAL_DATA`) for the tests that read
//! it in place: a file there (or `None` after saying on stderr why the test is skipped), the STS
//! 2024 mask's teeth, and the phantom whose true teeth are those teeth.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::PathBuf;
use toothfuse::TriMesh;
use toothfuse::arch::Jaw;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::volume::{Frame, LabelVolume, SurfaceOptions, VolumeScheme, surface_teeth};

/// The STS 2024 label volume (FDI labels, 0.25 mm, LPS affine), relative to the real data.
pub const STS_MASK: &str = "cbct_toothseg_sts2024/Validation_0001_Mask.nii.gz";

/// `rel` under the real data folder, or `None` (with a SKIPPED message) when it is absent.
pub fn real(rel: &str) -> Option<PathBuf> {
    let Some(dir) = toothfuse::io::real_data_dir() else {
        eprintln!(
            "SKIPPED: real data folder not found (set TOOTHFUSE_REAL_DATA or provide ../shared/data/real)"
        );
        return None;
    };
    let p = dir.join(rel);
    if !p.exists() {
        eprintln!("SKIPPED: {} not found", p.display());
        return None;
    }
    Some(p)
}

/// The lower teeth (31-48) of a label volume, cropped to them.
pub fn lower_teeth(v: &LabelVolume) -> LabelVolume {
    v.relabeled(|l| if (31..=48).contains(&l) { l } else { 0 })
        .cropped_to_labels()
}

/// The STS mask's lower teeth in its LPS world, cropped to them; `None` when absent.
pub fn sts_lower_teeth() -> Option<LabelVolume> {
    let p = real(STS_MASK)?;
    let v = toothfuse::io::read_label_volume(&p, Frame::Lps)
        .unwrap()
        .volume;
    Some(lower_teeth(&v))
}

/// A full phantom of `jaw` whose true teeth are the teeth of `teeth` (FDI labels) surfaced in its
/// world.
pub fn phantom_on(teeth: &LabelVolume, jaw: Jaw, seed: u64) -> Phantom {
    let surfaced = surface_teeth(teeth, VolumeScheme::Fdi, &SurfaceOptions::default()).unwrap();
    let anatomy: BTreeMap<u8, TriMesh> = surfaced
        .teeth
        .into_iter()
        .map(|(f, t)| (f, t.mesh))
        .collect();
    Phantom::generate(&PhantomOptions {
        seed,
        jaw,
        variant: Variant::Full,
        anatomy: Some(anatomy),
        ..Default::default()
    })
    .expect("phantom on the given teeth")
}
