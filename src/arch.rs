//! FDI tooth numbering: validation, jaw detection, arch order and neighbours.
//!
//! FDI two-digit numbers: quadrant 1–4 (permanent, teeth 1–8) or 5–8 (primary, teeth 1–5);
//! quadrants 1/2 (5/6) are upper right/left, 3/4 (7/8) lower left/right.

use crate::{Error, Result};

/// Upper (maxilla) or lower (mandible) jaw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Jaw {
    /// Maxilla: FDI quadrants 1, 2, 5, 6.
    Upper,
    /// Mandible: FDI quadrants 3, 4, 7, 8.
    Lower,
}

/// Kind of tooth by position in its quadrant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ToothType {
    /// Positions 1–2.
    Incisor,
    /// Position 3.
    Canine,
    /// Positions 4–5 (permanent).
    Premolar,
    /// Positions 6–8 (permanent) or 4–5 (primary).
    Molar,
}

/// True for a valid FDI number (11–18, 21–28, 31–38, 41–48, 51–55, …, 81–85).
pub fn is_valid_fdi(fdi: i32) -> bool {
    let (q, t) = (fdi / 10, fdi % 10);
    match q {
        1..=4 => (1..=8).contains(&t),
        5..=8 => (1..=5).contains(&t),
        _ => false,
    }
}

/// Checks an FDI number, with a message that says what is accepted.
pub fn check_fdi(fdi: i32) -> Result<u8> {
    if is_valid_fdi(fdi) {
        Ok(fdi as u8)
    } else {
        Err(Error::InvalidArgument(format!(
            "{fdi} is not an FDI tooth number (expected 11-18, 21-28, 31-38, 41-48 or primary 51-55 ... 81-85)"
        )))
    }
}

/// The jaw an FDI number belongs to.
pub fn jaw_of(fdi: u8) -> Jaw {
    match fdi / 10 {
        1 | 2 | 5 | 6 => Jaw::Upper,
        _ => Jaw::Lower,
    }
}

/// The tooth type of an FDI number.
pub fn tooth_type(fdi: u8) -> ToothType {
    let (q, t) = (fdi / 10, fdi % 10);
    let primary = q >= 5;
    match t {
        1 | 2 => ToothType::Incisor,
        3 => ToothType::Canine,
        4 | 5 if !primary => ToothType::Premolar,
        _ => ToothType::Molar,
    }
}

/// Position along the arch from the patient's right distal end to the left distal end:
/// negative on the right side (quadrants 1, 4, 5, 8), positive on the left; the magnitude grows
/// distally. Primary teeth sit between permanent positions so mixed dentitions still order.
pub fn arch_position(fdi: u8) -> i32 {
    let (q, t) = ((fdi / 10) as i32, (fdi % 10) as i32);
    let right = matches!(q, 1 | 4 | 5 | 8);
    let mag = if q >= 5 { 2 * t - 1 } else { 2 * t };
    if right { -mag } else { mag }
}

/// Detects the jaw of a set of teeth; fails when the set is empty or mixes jaws (naming a tooth
/// of each).
pub fn detect_jaw(teeth: &[u8]) -> Result<Jaw> {
    let first = *teeth
        .first()
        .ok_or_else(|| Error::MissingData("no teeth given".into()))?;
    let jaw = jaw_of(first);
    if let Some(&other) = teeth.iter().find(|&&t| jaw_of(t) != jaw) {
        return Err(Error::InvalidArgument(format!(
            "teeth from both jaws in one set: {first} is {:?}, {other} is {:?}",
            jaw,
            jaw_of(other)
        )));
    }
    Ok(jaw)
}

/// Sorts teeth in arch order (right distal end first), dropping duplicates.
pub fn arch_order(teeth: &[u8]) -> Vec<u8> {
    let mut v = teeth.to_vec();
    v.sort_by_key(|&t| (arch_position(t), t));
    v.dedup();
    v
}

/// The previous and next present teeth of `fdi` in arch order (gaps from missing teeth skipped).
pub fn neighbours(present: &[u8], fdi: u8) -> (Option<u8>, Option<u8>) {
    let order = arch_order(present);
    match order.iter().position(|&t| t == fdi) {
        Some(i) => (
            i.checked_sub(1).map(|j| order[j]),
            order.get(i + 1).copied(),
        ),
        None => (None, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validity() {
        for f in [11, 18, 21, 28, 31, 38, 41, 48, 51, 55, 85] {
            assert!(is_valid_fdi(f), "{f}");
        }
        for f in [0, 10, 19, 56, 90, 9, 100, -11] {
            assert!(!is_valid_fdi(f), "{f}");
        }
        assert!(check_fdi(19).unwrap_err().to_string().contains("19"));
    }

    #[test]
    fn upper_arch_order_runs_18_to_28() {
        let all: Vec<u8> = (11..=18).chain(21..=28).rev().collect();
        let o = arch_order(&all);
        let want: Vec<u8> = (11..=18).rev().chain(21..=28).collect();
        assert_eq!(o, want);
        assert_eq!(detect_jaw(&o).unwrap(), Jaw::Upper);
    }

    #[test]
    fn lower_order_and_neighbours_skip_gaps() {
        let present = [36, 34, 33, 31, 41, 42, 46];
        assert_eq!(arch_order(&present), vec![46, 42, 41, 31, 33, 34, 36]);
        assert_eq!(neighbours(&present, 31), (Some(41), Some(33)));
        assert_eq!(neighbours(&present, 46), (None, Some(42)));
        assert_eq!(neighbours(&present, 36), (Some(34), None));
        assert_eq!(detect_jaw(&present).unwrap(), Jaw::Lower);
        assert!(detect_jaw(&[11, 31]).is_err());
    }

    #[test]
    fn types() {
        assert_eq!(tooth_type(11), ToothType::Incisor);
        assert_eq!(tooth_type(43), ToothType::Canine);
        assert_eq!(tooth_type(25), ToothType::Premolar);
        assert_eq!(tooth_type(36), ToothType::Molar);
        assert_eq!(tooth_type(75), ToothType::Molar);
    }
}
