//! Detecting the tooth numbering of a label set (FDI, Universal 1–32, Mesh Labeler ordinals)
//! and converting labels to FDI.
//!
//! Detection decides only on evidence: the array's name (`UniversalID`, `PredictedID` →
//! Universal; a name containing `fdi` → FDI), the file format (Teeth3DS JSON → FDI), or values
//! valid in one numbering only. Values 11–18, 21–28, 31 and 32 are valid FDI and valid 1–32
//! numbers; a set of only those is read as FDI when that makes it one jaw while the 1–32 reading
//! spans both jaws (an IOS holds one jaw), and is refused as ambiguous otherwise.

use super::teeth::{LabelScheme, universal_to_fdi};
use crate::arch::{Jaw, is_valid_fdi, jaw_of};
use crate::{Error, Result};
use std::collections::BTreeSet;

/// The numbering detected for a label set and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Detected {
    /// The numbering.
    pub scheme: LabelScheme,
    /// The evidence, for `toothfuse info` and messages.
    pub reason: String,
}

/// What array names say about the numbering: `Some` for names that name it.
fn scheme_of_name(name: &str) -> Option<LabelScheme> {
    let l = name.to_ascii_lowercase().replace(['_', ' ', '-'], "");
    if l.contains("universal") || l == "predictedid" || l.contains("unn") {
        Some(LabelScheme::Universal)
    } else if l.contains("fdi") {
        Some(LabelScheme::Fdi)
    } else {
        None
    }
}

fn one_jaw(fdis: impl IntoIterator<Item = u8>) -> bool {
    let jaws: BTreeSet<Jaw> = fdis.into_iter().map(jaw_of).collect();
    jaws.len() <= 1
}

/// Detects the numbering of `labels` (gingiva 0 and, for 1–32 numbering, DCBIA's gingiva 33
/// ignored). `array` is the name of the array they came from, `teeth3ds_json` true for a
/// Teeth3DS label file. `what` names the input in errors, which say which `--labels` to pass.
pub fn detect_scheme(
    what: &str,
    array: Option<&str>,
    teeth3ds_json: bool,
    labels: &[i32],
) -> Result<Detected> {
    let values: BTreeSet<i32> = labels.iter().copied().filter(|&l| l != 0).collect();
    let shown = || {
        values
            .iter()
            .map(i32::to_string)
            .collect::<Vec<_>>()
            .join(" ")
    };
    let fdi_ok = values.iter().all(|&v| is_valid_fdi(v));
    let u_ok = values.iter().all(|&v| (1..=33).contains(&v));
    let check = |scheme: LabelScheme, reason: String| -> Result<Detected> {
        let ok = match scheme {
            LabelScheme::Fdi => fdi_ok,
            _ => u_ok,
        };
        if ok {
            Ok(Detected { scheme, reason })
        } else {
            Err(Error::InvalidArgument(format!(
                "{what}: {reason}, but the labels ({}) are not all valid {} numbers",
                shown(),
                scheme.name()
            )))
        }
    };
    if teeth3ds_json {
        return check(
            LabelScheme::Fdi,
            "Teeth3DS label JSON (FDI by format)".into(),
        );
    }
    if let Some(name) = array
        && let Some(s) = scheme_of_name(name)
    {
        return check(s, format!("array name {name:?}"));
    }
    if values.is_empty() {
        return Ok(Detected {
            scheme: LabelScheme::Fdi,
            reason: "no tooth labels".into(),
        });
    }
    let range = || {
        format!(
            "values {}..{}",
            values.first().copied().unwrap_or(0),
            values.last().copied().unwrap_or(0)
        )
    };
    match (fdi_ok, u_ok) {
        (true, false) => Ok(Detected {
            scheme: LabelScheme::Fdi,
            reason: format!("{} (only FDI numbers, some above 32)", range()),
        }),
        (false, true) => Ok(Detected {
            scheme: LabelScheme::Universal,
            reason: format!(
                "{} (1-32 numbering: Universal; Mesh Labeler ordinals map the same)",
                range()
            ),
        }),
        (true, true) => {
            let as_fdi = one_jaw(values.iter().map(|&v| v as u8));
            let as_u = one_jaw(values.iter().filter_map(|&v| universal_to_fdi(v)));
            if as_fdi && !as_u {
                Ok(Detected {
                    scheme: LabelScheme::Fdi,
                    reason: format!(
                        "{} (valid FDI and 1-32 numbers; FDI gives one jaw, 1-32 both)",
                        range()
                    ),
                })
            } else {
                Err(Error::InvalidArgument(format!(
                    "{what}: the tooth numbering is ambiguous: labels {} are valid both as FDI \
                     and as Universal/ordinal numbers; pass --labels fdi, --labels universal or \
                     --labels meshlabeler",
                    shown()
                )))
            }
        }
        (false, false) => Err(Error::InvalidArgument(format!(
            "{what}: labels {} fit no known tooth numbering (FDI 11-48/51-85, Universal 1-32, \
             Mesh Labeler ordinals); check the label array or pass --labels",
            shown()
        ))),
    }
}

/// Converts labels in place to FDI by `scheme` (gingiva stays 0; 33, DCBIA's gingiva in 1–32
/// numbering, becomes 0). Errors name the first label that does not convert.
pub fn labels_to_fdi(scheme: LabelScheme, labels: &mut [i32]) -> Result<()> {
    for l in labels.iter_mut() {
        if scheme.is_gingiva(*l) {
            *l = 0;
        } else {
            *l = scheme.to_fdi(*l)? as i32;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn det(array: Option<&str>, labels: &[i32]) -> Result<LabelScheme> {
        detect_scheme("x", array, false, labels).map(|d| d.scheme)
    }

    #[test]
    fn names_decide() {
        assert_eq!(
            det(Some("UniversalID"), &[11, 12]).unwrap(),
            LabelScheme::Universal
        );
        assert_eq!(
            det(Some("PredictedID"), &[3, 33]).unwrap(),
            LabelScheme::Universal
        );
        assert_eq!(det(Some("FDI"), &[11, 21]).unwrap(), LabelScheme::Fdi);
        assert!(det(Some("UniversalID"), &[41]).is_err());
        assert!(det(Some("fdi_label"), &[9]).is_err());
    }

    #[test]
    fn values_decide_when_unambiguous() {
        assert_eq!(
            det(Some("label"), &[0, 31, 36, 47]).unwrap(),
            LabelScheme::Fdi
        );
        assert_eq!(det(None, &[0, 2, 9, 15]).unwrap(), LabelScheme::Universal);
        assert_eq!(det(None, &[11, 17, 21, 27]).unwrap(), LabelScheme::Fdi);
        let e = det(None, &[31, 32]).unwrap_err().to_string();
        assert!(e.contains("ambiguous") && e.contains("--labels"), "{e}");
        assert!(det(None, &[11, 99]).is_err());
    }

    #[test]
    fn conversion_maps_gingiva() {
        let mut l = vec![0, 1, 8, 9, 33];
        labels_to_fdi(LabelScheme::Universal, &mut l).unwrap();
        assert_eq!(l, vec![0, 18, 11, 21, 0]);
        let mut l = vec![33];
        labels_to_fdi(LabelScheme::Fdi, &mut l).unwrap();
        assert_eq!(l, vec![33]);
    }
}
