//! Binary PLY payloads read in bulk. `ply-rs-bw` parses the header; its payload reader builds
//! one element value per vertex and per face (an allocation per face list), which made reading
//! a scan several times slower than the disk. Here the `vertex` and `face` elements of a binary
//! payload are decoded straight from the bytes by a plan made from the header, every count and
//! list length checked against the bytes left before anything is allocated. The results are
//! those of the crate's reader (a property test compares the two on random layouts, types,
//! byte orders and damaged files).

use super::ply::PlyVertex;
use ply_rs_bw::ply::{ElementDef, PropertyType, ScalarType};

/// The faces of a PLY file, flat: every face's index list in `idx`, face `f`'s at
/// `idx[start[f]..start[f + 1]]`.
#[derive(Debug, Default, PartialEq)]
pub(super) struct Faces {
    pub idx: Vec<i64>,
    pub start: Vec<usize>,
    pub label: Vec<Option<f64>>,
    /// The first face whose index property is not a list of integers.
    pub not_integers: Option<usize>,
}

impl Faces {
    /// An empty set of faces with room for `n`.
    pub fn with_capacity(n: usize) -> Faces {
        let mut start = Vec::with_capacity(n + 1);
        start.push(0);
        Faces {
            idx: Vec::with_capacity(3 * n),
            start,
            label: Vec::with_capacity(n),
            not_integers: None,
        }
    }

    /// Number of faces.
    pub fn len(&self) -> usize {
        self.start.len() - 1
    }

    /// Face `f`'s index list.
    pub fn indices(&self, f: usize) -> &[i64] {
        &self.idx[self.start[f]..self.start[f + 1]]
    }
}

/// Bytes of a payload being read, with the byte order.
pub(super) struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
    big: bool,
}

fn size_of(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `bytes` (big-endian when `big`).
    pub fn new(bytes: &'a [u8], big: bool) -> Cursor<'a> {
        Cursor { bytes, at: 0, big }
    }

    fn left(&self) -> usize {
        self.bytes.len() - self.at
    }

    /// The next `n` bytes, the cursor moved past them.
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let b = self
            .at
            .checked_add(n)
            .and_then(|end| self.bytes.get(self.at..end))
            .ok_or_else(|| format!("the payload ends at byte {}", self.bytes.len()))?;
        self.at += n;
        Ok(b)
    }

    /// A scalar as `f64` (the crate's reader gives every scalar type's value exactly; the
    /// integer types hold at most 32 bits, exact in `f64`).
    fn scalar(&mut self, t: &ScalarType) -> Result<f64, String> {
        let b = self.take(size_of(t))?;
        Ok(scalar_at(b, t, self.big))
    }

    /// An integer item of a list (`None` for a floating-point type, whose bytes are skipped).
    fn integer(&mut self, t: &ScalarType) -> Result<Option<i64>, String> {
        let b = self.take(size_of(t))?;
        Ok(match t {
            ScalarType::Float | ScalarType::Double => None,
            // At most 32 bits: exact in `f64` and back.
            _ => Some(scalar_at(b, t, self.big) as i64),
        })
    }

    /// A list's length: a non-negative integer of the count type.
    fn count(&mut self, t: &ScalarType) -> Result<usize, String> {
        match t {
            ScalarType::Float | ScalarType::Double => Err("a list length is not an integer".into()),
            _ => {
                let n = self.integer(t)?.unwrap_or(-1);
                usize::try_from(n).map_err(|_| format!("a list length is negative ({n})"))
            }
        }
    }

    fn skip(&mut self, n: usize) -> Result<(), String> {
        self.take(n).map(|_| ())
    }

    /// Skips a list of `n` items of type `t`, checked against the bytes left.
    fn skip_list(&mut self, n: usize, t: &ScalarType) -> Result<(), String> {
        self.skip(n.saturating_mul(size_of(t)))
    }
}

/// What one property of an element is read for.
enum Slot {
    Coordinate(usize),
    Label,
    Indices,
    Skip,
}

/// The properties of `def` in payload order, each with its slot (`indices_key`: the face
/// element's index list; `label`: the chosen label property).
fn plan<'d>(
    def: &'d ElementDef,
    coordinates: bool,
    indices_key: Option<&str>,
    label: Option<&str>,
) -> Vec<(Slot, &'d PropertyType)> {
    // As the crate's reader fills a face: `vertex_index` before `vertex_indices` is taken as
    // the index list (then replaced), so it is no label there.
    let mut indices_seen = false;
    def.properties
        .iter()
        .map(|(k, p)| {
            let slot = match k.as_str() {
                "x" if coordinates => Slot::Coordinate(0),
                "y" if coordinates => Slot::Coordinate(1),
                "z" if coordinates => Slot::Coordinate(2),
                k if Some(k) == indices_key => {
                    indices_seen = true;
                    Slot::Indices
                }
                "vertex_index" if indices_key == Some("vertex_indices") && !indices_seen => {
                    Slot::Skip
                }
                k if Some(k) == label => Slot::Label,
                _ => Slot::Skip,
            };
            (slot, &p.data_type)
        })
        .collect()
}

/// Reads one property of type `t` for `slot`; returns its scalar value where it has one.
fn read_property(
    c: &mut Cursor,
    t: &PropertyType,
    slot: &Slot,
    list_out: Option<&mut Faces>,
) -> Result<Option<f64>, String> {
    match t {
        PropertyType::Scalar(s) => {
            let v = c.scalar(s)?;
            if matches!(slot, Slot::Indices)
                && let Some(faces) = list_out
            {
                faces.not_integers.get_or_insert(faces.len());
            }
            Ok(Some(v))
        }
        PropertyType::List(count_type, item) => {
            let n = c.count(count_type)?;
            match (slot, list_out) {
                (Slot::Indices, Some(faces)) => {
                    let Some(len) = n.checked_mul(size_of(item)).filter(|&b| b <= c.left()) else {
                        return Err(format!("a list of {n} items runs past the payload's end"));
                    };
                    let items = &c.bytes[c.at..c.at + len];
                    c.at += len;
                    if !integers_into(items, item, c.big, &mut faces.idx) {
                        faces.not_integers.get_or_insert(faces.len());
                    }
                }
                _ => c.skip_list(n, item)?,
            }
            Ok(None)
        }
    }
}

/// Checks that `count` items of at least `min_size` bytes each fit in the bytes left, so that
/// a damaged header's count is refused before anything is allocated for it.
fn check_count(c: &Cursor, def: &ElementDef, min_size: usize) -> Result<(), String> {
    if def.count.checked_mul(min_size).is_none_or(|b| b > c.left()) {
        return Err(format!(
            "element `{}` declares {} items of at least {min_size} bytes, {} bytes are left",
            def.name,
            def.count,
            c.left()
        ));
    }
    Ok(())
}

/// The smallest size of one item of `def` (a list at its count alone).
fn min_item_size(def: &ElementDef) -> usize {
    def.properties
        .values()
        .map(|p| match &p.data_type {
            PropertyType::Scalar(s) => size_of(s),
            PropertyType::List(n, _) => size_of(n),
        })
        .sum()
}

/// The first `N` bytes of `b` in little-endian order (reversed from big-endian).
fn bytes_le<const N: usize>(b: &[u8], big: bool) -> [u8; N] {
    let mut a = [0u8; N];
    a.copy_from_slice(&b[..N]);
    if big {
        a.reverse();
    }
    a
}

/// The scalar of type `t` at the start of `b` as `f64` (what [`Cursor::scalar`] reads).
fn scalar_at(b: &[u8], t: &ScalarType, big: bool) -> f64 {
    match t {
        ScalarType::Char => i8::from_le_bytes(bytes_le(b, big)).into(),
        ScalarType::UChar => u8::from_le_bytes(bytes_le(b, big)).into(),
        ScalarType::Short => i16::from_le_bytes(bytes_le(b, big)).into(),
        ScalarType::UShort => u16::from_le_bytes(bytes_le(b, big)).into(),
        ScalarType::Int => i32::from_le_bytes(bytes_le(b, big)).into(),
        ScalarType::UInt => u32::from_le_bytes(bytes_le(b, big)).into(),
        ScalarType::Float => f32::from_le_bytes(bytes_le(b, big)).into(),
        ScalarType::Double => f64::from_le_bytes(bytes_le(b, big)),
    }
}

/// Appends the integer items of a list (`items`: its bytes, items of type `t`) to `out`, as
/// [`Cursor::integer`] reads them one by one; `false` (nothing appended) for a floating-point
/// item type.
fn integers_into(items: &[u8], t: &ScalarType, big: bool, out: &mut Vec<i64>) -> bool {
    macro_rules! each {
        ($ty:ty, $n:literal) => {
            out.extend(
                items
                    .chunks_exact($n)
                    .map(|b| i64::from(<$ty>::from_le_bytes(bytes_le(b, big)))),
            )
        };
    }
    match t {
        ScalarType::Char => each!(i8, 1),
        ScalarType::UChar => each!(u8, 1),
        ScalarType::Short => each!(i16, 2),
        ScalarType::UShort => each!(u16, 2),
        ScalarType::Int => each!(i32, 4),
        ScalarType::UInt => each!(u32, 4),
        ScalarType::Float | ScalarType::Double => return false,
    }
    true
}

/// The vertex records of an element whose properties are all scalars: one fixed-size record
/// each, decoded at fixed offsets (only the coordinates and the label; the rest skipped).
/// `None` where a property is a list.
fn fixed_vertices(
    c: &mut Cursor,
    def: &ElementDef,
    props: &[(Slot, &PropertyType)],
) -> Option<Vec<PlyVertex>> {
    let mut used = Vec::new();
    let mut size = 0;
    for (slot, t) in props {
        let PropertyType::Scalar(s) = t else {
            return None;
        };
        if !matches!(slot, Slot::Skip) {
            used.push((slot, s, size));
        }
        size += size_of(s);
    }
    // `check_count` has made sure the records fit in the bytes left.
    let len = def.count * size;
    let records = &c.bytes[c.at..c.at + len];
    c.at += len;
    let mut out = Vec::with_capacity(def.count);
    for rec in records.chunks_exact(size.max(1)).take(def.count) {
        let mut v = PlyVertex::default();
        for &(slot, t, at) in &used {
            let value = Some(scalar_at(&rec[at..], t, c.big));
            match slot {
                Slot::Coordinate(k) => v.xyz[*k] = value,
                _ => v.label = value,
            }
        }
        out.push(v);
    }
    Some(out)
}

/// Reads the `vertex` element: coordinates and the label property `label`'s value.
pub(super) fn vertices(
    c: &mut Cursor,
    def: &ElementDef,
    label: Option<&str>,
) -> Result<Vec<PlyVertex>, String> {
    check_count(c, def, min_item_size(def))?;
    let props = plan(def, true, None, label);
    if let Some(out) = fixed_vertices(c, def, &props) {
        return Ok(out);
    }
    let mut out = Vec::with_capacity(def.count);
    for i in 0..def.count {
        let mut v = PlyVertex::default();
        for (slot, t) in &props {
            let value = read_property(c, t, slot, None).map_err(|e| at(def, i, e))?;
            match slot {
                Slot::Coordinate(k) => v.xyz[*k] = value,
                Slot::Label => v.label = value,
                _ => {}
            }
        }
        out.push(v);
    }
    Ok(out)
}

/// Reads the `face` element: each face's index list (`key`) and the label property `label`'s
/// value.
pub(super) fn faces(
    c: &mut Cursor,
    def: &ElementDef,
    key: &str,
    label: Option<&str>,
) -> Result<Faces, String> {
    check_count(c, def, min_item_size(def))?;
    let props = plan(def, false, Some(key), label);
    let mut out = Faces::with_capacity(def.count);
    for f in 0..def.count {
        let mut l = None;
        for (slot, t) in &props {
            let value = read_property(c, t, slot, Some(&mut out)).map_err(|e| at(def, f, e))?;
            if matches!(slot, Slot::Label) {
                l = value;
            }
        }
        out.label.push(l);
        out.start.push(out.idx.len());
    }
    Ok(out)
}

/// Skips an element the reader does not use.
pub(super) fn skip(c: &mut Cursor, def: &ElementDef) -> Result<(), String> {
    check_count(c, def, min_item_size(def))?;
    let props = plan(def, false, None, None);
    for i in 0..def.count {
        for (slot, t) in &props {
            read_property(c, t, slot, None).map_err(|e| at(def, i, e))?;
        }
    }
    Ok(())
}

fn at(def: &ElementDef, i: usize, e: String) -> String {
    format!("element `{}` item {i}: {e}", def.name)
}

#[cfg(test)]
mod tests {
    use super::super::ply::read_ply;
    use crate::phantom::rng::Rng;

    const TYPES: [&str; 8] = [
        "char", "uchar", "short", "ushort", "int", "uint", "float", "double",
    ];

    /// Appends `v` as PLY type `t` in the byte order.
    fn put(out: &mut Vec<u8>, t: &str, v: f64, big: bool) {
        let mut b: Vec<u8> = match t {
            "char" => (v as i8).to_le_bytes().to_vec(),
            "uchar" => (v as u8).to_le_bytes().to_vec(),
            "short" => (v as i16).to_le_bytes().to_vec(),
            "ushort" => (v as u16).to_le_bytes().to_vec(),
            "int" => (v as i32).to_le_bytes().to_vec(),
            "uint" => (v as u32).to_le_bytes().to_vec(),
            "float" => (v as f32).to_le_bytes().to_vec(),
            _ => v.to_le_bytes().to_vec(),
        };
        if big {
            b.reverse();
        }
        out.extend(b);
    }

    /// One property of a random layout: its name and its type (`count` set for a list).
    struct Prop {
        name: String,
        ty: &'static str,
        count: Option<&'static str>,
    }

    fn pick<T: Copy>(rng: &mut Rng, xs: &[T]) -> T {
        xs[rng.below(xs.len())]
    }

    /// A random binary PLY: vertex coordinates of any type in any order among extra scalars
    /// and lists (a label among them), faces of 3-5 corners with any count and index types
    /// (sometimes floating-point), an optional face label, an extra element before, between or
    /// after, indices and labels sometimes out of range or fractional.
    fn random_ply(rng: &mut Rng) -> Vec<u8> {
        let big = rng.below(2) == 1;
        let scalar = |rng: &mut Rng, name: &str, types: &[&'static str]| Prop {
            name: name.into(),
            ty: pick(rng, types),
            count: None,
        };
        let mut vprops: Vec<Prop> = ["x", "y", "z"]
            .iter()
            .map(|n| scalar(rng, n, &["float", "double", "float", "int", "short"]))
            .collect();
        for name in ["label", "quality", "nx"] {
            if rng.below(2) == 1 {
                vprops.push(scalar(rng, name, &TYPES));
            }
        }
        if rng.below(4) == 0 {
            vprops.push(Prop {
                name: "extra".into(),
                ty: pick(rng, &TYPES),
                count: Some(pick(rng, &["uchar", "int"])),
            });
        }
        for i in (1..vprops.len()).rev() {
            vprops.swap(i, rng.below(i + 1));
        }
        let index_types: &[&'static str] = if rng.below(10) == 0 {
            &TYPES
        } else {
            &["int", "uint", "ushort", "short"]
        };
        let mut fprops = vec![Prop {
            name: pick(rng, &["vertex_indices", "vertex_indices", "vertex_index"]).into(),
            ty: pick(rng, index_types),
            count: Some(pick(rng, &["uchar", "char", "ushort", "int", "uint"])),
        }];
        if rng.below(2) == 1 {
            fprops.push(scalar(rng, "label", &TYPES));
        }
        if rng.below(4) == 0 {
            fprops.push(scalar(rng, "flags", &TYPES));
        }
        for i in (1..fprops.len()).rev() {
            fprops.swap(i, rng.below(i + 1));
        }
        let eprops = vec![
            scalar(rng, "weight", &TYPES),
            Prop {
                name: "ends".into(),
                ty: pick(rng, &TYPES),
                count: Some("uchar"),
            },
        ];
        let (nv, nf, ne) = (3 + rng.below(20), rng.below(30), rng.below(5));
        let elements = [("vertex", nv, &vprops), ("face", nf, &fprops)];
        let extra_at = rng.below(3);
        let mut order: Vec<(&str, usize, &Vec<Prop>)> = elements.to_vec();
        order.insert(extra_at, ("edge", ne, &eprops));
        let mut out = format!(
            "ply\nformat binary_{}_endian 1.0\n",
            if big { "big" } else { "little" }
        )
        .into_bytes();
        for (name, n, props) in &order {
            out.extend(format!("element {name} {n}\n").bytes());
            for p in props.iter() {
                let line = match p.count {
                    Some(c) => format!("property list {c} {} {}\n", p.ty, p.name),
                    None => format!("property {} {}\n", p.ty, p.name),
                };
                out.extend(line.bytes());
            }
        }
        out.extend(b"end_header\n");
        for (name, n, props) in &order {
            for _ in 0..*n {
                for p in props.iter() {
                    let value = |rng: &mut Rng| match p.name.as_str() {
                        "label" if rng.below(800) == 0 => 11.5,
                        "label" => (11 + rng.below(8)) as f64,
                        "vertex_indices" | "vertex_index" if rng.below(3000) == 0 => {
                            nv as f64 + 2.0
                        }
                        "vertex_indices" | "vertex_index" => rng.below(nv) as f64,
                        _ => rng.below(100) as f64 * 0.25,
                    };
                    match p.count {
                        None => {
                            let v = value(rng);
                            put(&mut out, p.ty, v, big);
                        }
                        Some(c) => {
                            let k = if *name == "face" {
                                3 + rng.below(3)
                            } else {
                                rng.below(4)
                            };
                            put(&mut out, c, k as f64, big);
                            for _ in 0..k {
                                let v = value(rng);
                                put(&mut out, p.ty, v, big);
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// The bulk reader answers as the crate's reader on random layouts, types and byte
    /// orders, and on the same files cut short, with a byte flipped or a count changed: the
    /// same mesh, labels and arrays, or an error from both.
    #[test]
    fn bulk_reader_answers_as_the_crate_reader() {
        let mut rng = Rng::new(17);
        let (mut same_ok, mut same_err) = (0, 0);
        for case in 0..3000 {
            let mut bytes = random_ply(&mut rng);
            match case % 4 {
                1 => {
                    let cut = rng.below(bytes.len());
                    bytes.truncate(cut);
                }
                2 => {
                    let i = rng.below(bytes.len());
                    bytes[i] ^= 1 << rng.below(8);
                }
                _ => {}
            }
            let bulk = read_ply("t.ply", &bytes, None, true);
            let each = read_ply("t.ply", &bytes, None, false);
            match (bulk, each) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(a.mesh, b.mesh, "case {case}");
                    assert_eq!(a.label_array, b.label_array, "case {case}");
                    assert_eq!(a.arrays, b.arrays, "case {case}");
                    same_ok += 1;
                }
                (Err(_), Err(_)) => same_err += 1,
                (a, b) => panic!(
                    "case {case}: bulk {:?}, crate {:?}",
                    a.map(|m| m.mesh.mesh.triangles.len()),
                    b.map(|m| m.mesh.mesh.triangles.len())
                ),
            }
        }
        assert!(
            same_ok > 1000 && same_err > 500,
            "{same_ok} read, {same_err} refused"
        );
    }
}
