//! Cases in the layout of `../shared/data/foreign/` (a jaw from an independent generator, with
//! its truth): `ios.ply` (labeled IOS jaw), `cbct.ply` (labeled CBCT teeth) and
//! `truth/transforms.json` whose `ios_from_cbct[fdi]` is the true 4×4 row-major map of tooth
//! `fdi` from the CBCT frame to the IOS frame. Used by the tests, examples and benchmarks that
//! check the method on jaws the project did not make.

use crate::fuse::ToothTransforms;
use crate::mesh::{LabeledMesh, TriMesh};
use crate::{Error, Result, Rigid};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One case: the inputs and the true per-tooth transforms into the IOS frame.
#[derive(Clone, Debug)]
pub struct ForeignCase {
    /// The labeled IOS jaw.
    pub ios: LabeledMesh,
    /// The CBCT teeth by FDI.
    pub cbct: BTreeMap<u8, TriMesh>,
    /// True transforms: CBCT → IOS per tooth, IOS → output the identity.
    pub truth: BTreeMap<u8, ToothTransforms>,
}

/// The case folders under `../shared/data/foreign/` beside the crate, in name order; empty when
/// that folder is absent.
pub fn case_dirs() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/foreign");
    let Ok(rd) = std::fs::read_dir(&root) else {
        return Vec::new();
    };
    let mut dirs: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("truth/transforms.json").is_file())
        .collect();
    dirs.sort();
    dirs
}

/// Reads the true transforms of a case folder.
pub fn read_truth(dir: &Path) -> Result<BTreeMap<u8, ToothTransforms>> {
    let path = dir.join("truth/transforms.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
    let bad = |what: &str| Error::InvalidArgument(format!("{}: {what}", path.display()));
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(&format!("not JSON: {e}")))?;
    let map = v["ios_from_cbct"]
        .as_object()
        .ok_or_else(|| bad("no ios_from_cbct object"))?;
    let mut out = BTreeMap::new();
    for (k, m) in map {
        let a: Vec<f64> = m
            .as_array()
            .into_iter()
            .flatten()
            .flat_map(|r| {
                r.as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|x| x.as_f64())
            })
            .collect();
        let a: [f64; 16] = a
            .try_into()
            .map_err(|_| bad(&format!("tooth {k}: not a 4x4 matrix of numbers")))?;
        let fdi = k
            .parse::<u8>()
            .map_err(|_| bad(&format!("key {k:?} is not a tooth number")))?;
        let t = ToothTransforms {
            cbct_to_output: Rigid::from_row_major(&a),
            ios_to_output: Rigid::IDENTITY,
        };
        out.insert(fdi, t);
    }
    Ok(out)
}

/// Reads a whole case folder.
pub fn read_case(dir: &Path) -> Result<ForeignCase> {
    Ok(ForeignCase {
        ios: crate::io::read_mesh(dir.join("ios.ply"))?,
        cbct: crate::io::read_teeth(dir.join("cbct.ply"))?,
        truth: read_truth(dir)?,
    })
}
