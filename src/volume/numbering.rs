//! What the label values of a CBCT volume mean: which are teeth, and their FDI numbers.

use crate::arch::check_fdi;
use crate::io::universal_to_fdi;
use crate::{Error, Result};

/// The numbering of a label volume's values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VolumeScheme {
    /// One label per tooth, the FDI number (STS 2024, most nnU-Net tooth models). Every
    /// non-zero label must be an FDI number.
    #[default]
    Fdi,
    /// One label per tooth, Universal / UNN 1–32. Every non-zero label must be 1–32.
    Universal,
    /// ToothFairy2: teeth at their FDI numbers 11–48; the other structures (jaw bones, canals,
    /// sinuses, pharynx, bridges, crowns, implants at 1–10, pulps and canals above 100) are not
    /// teeth and are skipped.
    ToothFairy2,
    /// DentalSegmentator: 1 maxilla, 2 mandible, 3 upper teeth, 4 lower teeth, 5 mandibular
    /// canal; no tooth numbers (one teeth label per jaw).
    DentalSegmentator,
}

impl VolumeScheme {
    /// `"fdi"`, `"universal"`, `"toothfairy2"` or `"dentalsegmentator"` (case-insensitive).
    pub fn from_name(name: &str) -> Option<VolumeScheme> {
        match name.to_ascii_lowercase().as_str() {
            "fdi" => Some(VolumeScheme::Fdi),
            "universal" => Some(VolumeScheme::Universal),
            "toothfairy2" => Some(VolumeScheme::ToothFairy2),
            "dentalsegmentator" => Some(VolumeScheme::DentalSegmentator),
            _ => None,
        }
    }

    /// True for schemes with one label per tooth.
    pub fn is_per_tooth(self) -> bool {
        self != VolumeScheme::DentalSegmentator
    }

    /// The FDI number of tooth label `label`, `None` for a label that is a known non-tooth
    /// structure of the scheme; an error names a label the scheme does not know.
    pub fn tooth_fdi(self, label: u16) -> Result<Option<u8>> {
        let l = label as i32;
        match self {
            VolumeScheme::Fdi => check_fdi(l).map(Some).map_err(|_| {
                Error::InvalidArgument(format!(
                    "volume label {label} is not an FDI tooth number (11-18, 21-28, 31-38, \
                     41-48, 51-85); choose the volume's numbering (universal, toothfairy2, \
                     dentalsegmentator)"
                ))
            }),
            VolumeScheme::Universal => universal_to_fdi(l).map(Some).ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "volume label {label} is outside 1-32 (Universal numbering)"
                ))
            }),
            VolumeScheme::ToothFairy2 => Ok(match l {
                11..=18 | 21..=28 | 31..=38 | 41..=48 => Some(l as u8),
                _ => None,
            }),
            VolumeScheme::DentalSegmentator => Ok(None),
        }
    }
}

/// True when the labels look like DentalSegmentator's classes: only values 1–5, with both or
/// one of the teeth classes 3 and 4 present.
pub fn looks_like_dentalsegmentator(labels: &[u16]) -> bool {
    !labels.is_empty()
        && labels.iter().all(|&l| (1..=5).contains(&l))
        && labels.iter().any(|&l| l == 3 || l == 4)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemes_map_labels() {
        assert_eq!(VolumeScheme::Fdi.tooth_fdi(36).unwrap(), Some(36));
        assert!(VolumeScheme::Fdi.tooth_fdi(3).is_err());
        assert_eq!(VolumeScheme::Universal.tooth_fdi(8).unwrap(), Some(11));
        assert_eq!(VolumeScheme::Universal.tooth_fdi(19).unwrap(), Some(36));
        assert!(VolumeScheme::Universal.tooth_fdi(33).is_err());
        assert_eq!(VolumeScheme::ToothFairy2.tooth_fdi(47).unwrap(), Some(47));
        assert_eq!(VolumeScheme::ToothFairy2.tooth_fdi(1).unwrap(), None);
        assert_eq!(VolumeScheme::ToothFairy2.tooth_fdi(111).unwrap(), None);
        assert!(looks_like_dentalsegmentator(&[1, 2, 3, 4, 5]));
        assert!(!looks_like_dentalsegmentator(&[1, 2, 5]));
        assert!(!looks_like_dentalsegmentator(&[3, 11]));
    }
}
