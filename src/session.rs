//! The session: the teeth a host has handed over, per modality, keyed by FDI number.
//!
//! This is the pure-Rust state behind the C ABI's `toothfuse_session` (see [`crate::ffi`]); it
//! knows nothing about C. Every tooth is validated on entry, so later stages (registration, crown
//! removal, stitching) can rely on it:
//!
//! * a CBCT tooth must be a closed, 2-manifold surface (every edge in exactly two faces);
//! * an IOS crown must be 2-manifold; it is open (its gingival margin is a boundary loop).
//!
//! Both must have finite coordinates, indices in range, at least one triangle, and no degenerate
//! (repeated-vertex or zero-area) or duplicate triangles. Adding a tooth whose FDI number is
//! already held in that modality replaces it. Every mutating call is all-or-nothing: on error the
//! session is exactly as before.
//!
//! Real scans rarely pass as they are (the Mesh Labeler example: 13 of 14 crowns have edges
//! shared by 3-4 faces or bow-tie vertices), so IOS repair can be switched on
//! ([`Session::set_ios_repair`]): each IOS crown then goes through
//! [`crate::mesh::repair_open_surface`] before validation (kept vertices keep their exact
//! positions; bow-tie vertices are duplicated; added hole-centre vertices have no source vertex,
//! [`NO_SOURCE`]). Off by default: input is then kept exactly or rejected.
//!
//! Results: [`Session::register`] registers the held teeth ([`crate::register`]),
//! [`Session::cut`] and [`Session::stitch`] run the two fusion stages with that registration, and
//! [`Session::fuse`] registers, cuts and stitches them in one call ([`crate::pipeline`]); each
//! keeps its result on the session. Any change of the held teeth (add, replace, remove, clear)
//! drops the results; a failed call keeps the previous results.

use crate::arch::{check_fdi, is_valid_fdi};
use crate::mesh::{
    LabelDomain, RepairOptions, RepairReport, ValidateOptions, ValidationReport,
    repair_open_surface, split_by_face_labels, split_by_vertex_labels,
};
use crate::pipeline::PipelineCut;
use crate::register::Registration;
use crate::{Error, Result, TriMesh};
use std::collections::BTreeMap;
use std::fmt;

mod results;
mod volume;

pub use results::{Fused, Notes};

/// Where a tooth mesh comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Modality {
    /// Intraoral scan: crowns only, open at the gingival margin, sharp detail.
    Ios,
    /// CBCT segmentation: whole closed teeth (crown and root), blurry crowns.
    Cbct,
}

impl fmt::Display for Modality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Modality::Ios => "IOS",
            Modality::Cbct => "CBCT",
        })
    }
}

impl Modality {
    /// The validation a tooth of this modality must pass.
    pub fn validate_options(self) -> ValidateOptions {
        ValidateOptions {
            require_closed: self == Modality::Cbct,
            allow_zero_area: false,
        }
    }
}

/// One validated tooth held by a session.
#[derive(Clone, Debug, PartialEq)]
pub struct Tooth {
    /// FDI number.
    pub fdi: u8,
    /// The geometry, exactly as given (positions bit for bit for f64 input).
    pub mesh: TriMesh,
    /// For each vertex of `mesh`, its index in the buffer the host passed (the identity for a
    /// single tooth; the jaw vertex index for a tooth split from a labeled jaw).
    pub source_vertex: Vec<u32>,
    /// Topology found by validation (boundary loops, components, ...).
    pub report: ValidationReport,
    /// What IOS repair changed, when repair was on for this tooth.
    pub repair: Option<RepairReport>,
}

/// `source_vertex` entry of a vertex that repair added (a hole centre).
pub const NO_SOURCE: u32 = u32::MAX;

/// What an IOS crown refused as given (not a manifold open surface) can be made to pass: the
/// IOS repair on entry, as the command line always runs it.
const IOS_REPAIR_REMEDY: &str = "IOS crowns are taken as given: scan exports often carry such \
     faults; turn the IOS repair on (toothfuse_session_set_ios_repair; Python: ios_repair=True; \
     the command line always repairs) to make each crown one manifold disk on entry, every kept \
     vertex at its given position";

/// The teeth handed over so far, per modality, keyed by FDI number.
#[derive(Clone, Debug, Default)]
pub struct Session {
    ios: BTreeMap<u8, Tooth>,
    cbct: BTreeMap<u8, Tooth>,
    ios_repair: Option<RepairOptions>,
    registration: Option<Registration>,
    cut: Option<PipelineCut>,
    fused: Option<Fused>,
    notes: Notes,
    /// Per tooth, the split of the last per-jaw label volume (added to the notes).
    split_notes: BTreeMap<u8, String>,
}

impl Session {
    /// An empty session.
    pub fn new() -> Self {
        Self::default()
    }

    /// Switches repair of IOS crowns on entry on (`Some`) or off (`None`, the default). Affects
    /// later adds only.
    pub fn set_ios_repair(&mut self, opts: Option<RepairOptions>) -> Result<()> {
        if let Some(o) = opts
            && !(o.max_hole_fraction.is_finite() && (0.0..=1.0).contains(&o.max_hole_fraction))
        {
            return Err(Error::InvalidArgument(format!(
                "max_hole_fraction {} is not in [0, 1]",
                o.max_hole_fraction
            )));
        }
        self.ios_repair = opts;
        Ok(())
    }

    /// The IOS repair options in force, if repair is on.
    pub fn ios_repair(&self) -> Option<RepairOptions> {
        self.ios_repair
    }

    /// Repairs (IOS, when on) and validates one tooth; `source` maps its vertices to the
    /// caller's buffer.
    fn prepare(
        &self,
        modality: Modality,
        fdi: u8,
        mesh: TriMesh,
        source: Vec<u32>,
    ) -> Result<Tooth> {
        let (mesh, source_vertex, repair) = match (modality, self.ios_repair) {
            (Modality::Ios, Some(opts)) if !mesh.triangles.is_empty() => {
                let (m, src, rep) = repair_open_surface(&mesh, &opts);
                let composed = src
                    .iter()
                    .map(|&s| {
                        if s == NO_SOURCE {
                            NO_SOURCE
                        } else {
                            source[s as usize]
                        }
                    })
                    .collect();
                (m, composed, Some(rep))
            }
            _ => (mesh, source, None),
        };
        let report = Self::validate_tooth(modality, fdi, &mesh).map_err(|e| {
            // A scan export's crown often carries such faults: say how to have it repaired.
            if modality == Modality::Ios
                && self.ios_repair.is_none()
                && e.kind() == crate::ErrorKind::NotManifold
            {
                Error::WithRemedy {
                    inner: Box::new(e),
                    remedy: IOS_REPAIR_REMEDY.to_string(),
                }
            } else {
                e
            }
        })?;
        crate::units::check_entry_scale(&mesh, &modality.to_string())
            .map_err(|e| e.in_tooth(fdi))?;
        Ok(Tooth {
            fdi,
            mesh,
            source_vertex,
            report,
            repair,
        })
    }

    /// The teeth held for `modality`, in FDI order.
    pub fn teeth(&self, modality: Modality) -> &BTreeMap<u8, Tooth> {
        match modality {
            Modality::Ios => &self.ios,
            Modality::Cbct => &self.cbct,
        }
    }

    fn teeth_mut(&mut self, modality: Modality) -> &mut BTreeMap<u8, Tooth> {
        match modality {
            Modality::Ios => &mut self.ios,
            Modality::Cbct => &mut self.cbct,
        }
    }

    /// FDI numbers held for `modality`, ascending.
    pub fn fdis(&self, modality: Modality) -> Vec<u8> {
        self.teeth(modality).keys().copied().collect()
    }

    /// The tooth `fdi` of `modality`; a `MissingData` error lists the teeth held when absent.
    pub fn tooth(&self, modality: Modality, fdi: i32) -> Result<&Tooth> {
        let key = check_fdi(fdi)?;
        self.teeth(modality).get(&key).ok_or_else(|| {
            let held = self.fdis(modality);
            let held = if held.is_empty() {
                "none".to_string()
            } else {
                held.iter()
                    .map(|t| t.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            Error::MissingData(format!(
                "no {modality} tooth {fdi} in the session ({modality} teeth held: {held})"
            ))
        })
    }

    /// Validates `mesh` as tooth `fdi` of `modality` (see the module docs for the rules).
    /// Errors name the tooth.
    pub fn validate_tooth(modality: Modality, fdi: u8, mesh: &TriMesh) -> Result<ValidationReport> {
        if mesh.triangles.is_empty() {
            return Err(
                Error::InvalidArgument(format!("{modality} tooth mesh has no triangles"))
                    .in_tooth(fdi),
            );
        }
        if u32::try_from(mesh.positions.len()).is_err() {
            return Err(Error::InvalidArgument(format!(
                "{} vertices exceed the u32 index range",
                mesh.positions.len()
            ))
            .in_tooth(fdi));
        }
        mesh.validate(&modality.validate_options())
            .map_err(|e| e.in_tooth(fdi))
    }

    /// Adds (or replaces) tooth `fdi` of `modality`. On error nothing changes. A tooth whose size
    /// no millimetre unit can give ([`crate::units::ENTRY_DIAGONAL_MM`]) is refused with
    /// `UnitMismatch`; sizes that are only implausible for a whole jaw are judged at registration.
    pub fn add_tooth(&mut self, modality: Modality, fdi: i32, mesh: TriMesh) -> Result<()> {
        let key = check_fdi(fdi)?;
        let source = (0..mesh.positions.len() as u32).collect();
        let tooth = self.prepare(modality, key, mesh, source)?;
        self.drop_results();
        self.teeth_mut(modality).insert(key, tooth);
        Ok(())
    }

    /// Splits a labeled jaw mesh by FDI label and adds (or replaces) every tooth found, all or
    /// nothing. Label 0 is gingiva and is dropped; any other label must be an FDI number (the
    /// error names the first bad label and the vertex or face carrying it). With per-vertex
    /// labels a face belongs to a tooth when all three of its vertices carry that label, so a
    /// crown ends at its margin. Teeth of `modality` not in the jaw are kept. The teeth's median
    /// size must be plausible in millimetres ([`crate::units::check_jaw_scales`]), else
    /// `UnitMismatch` names the modality and the likely unit. Returns the FDI numbers added,
    /// ascending.
    pub fn add_jaw(
        &mut self,
        modality: Modality,
        jaw: &TriMesh,
        labels: &[i32],
        domain: LabelDomain,
    ) -> Result<Vec<u8>> {
        let (what, whats, expected) = match domain {
            LabelDomain::Vertex => ("vertex", "vertices", jaw.positions.len()),
            LabelDomain::Face => ("face", "faces", jaw.triangles.len()),
        };
        if labels.len() != expected {
            return Err(Error::InvalidArgument(format!(
                "{} labels given but the jaw mesh has {expected} {whats} (one label per {what})",
                labels.len()
            )));
        }
        if let Some((i, &l)) = labels
            .iter()
            .enumerate()
            .find(|&(_, &l)| l != 0 && !is_valid_fdi(l))
        {
            return Err(Error::InvalidArgument(format!(
                "label {l} (on {what} {i}) is not an FDI tooth number; labels must be 0 (gingiva) \
                 or FDI 11-18, 21-28, 31-38, 41-48, 51-55 ... 81-85"
            )));
        }
        let parts = match domain {
            LabelDomain::Vertex => split_by_vertex_labels(jaw, labels)?,
            LabelDomain::Face => split_by_face_labels(jaw, labels)?,
        };
        let mut staged: Vec<Tooth> = Vec::new();
        for (label, part) in parts {
            if label == 0 {
                continue;
            }
            let fdi = check_fdi(label)?;
            staged.push(self.prepare(modality, fdi, part.mesh, part.source_vertex)?);
        }
        if staged.is_empty() {
            return Err(Error::MissingData(format!(
                "the {modality} jaw mesh has no tooth: no triangle carries an FDI label"
            )));
        }
        let meshes: BTreeMap<u8, TriMesh> =
            staged.iter().map(|t| (t.fdi, t.mesh.clone())).collect();
        match modality {
            Modality::Ios => crate::units::check_jaw_scales(&meshes, &BTreeMap::new()),
            Modality::Cbct => crate::units::check_jaw_scales(&BTreeMap::new(), &meshes),
        }?;
        let added = staged.iter().map(|t| t.fdi).collect();
        self.drop_results();
        let teeth = self.teeth_mut(modality);
        for t in staged {
            teeth.insert(t.fdi, t);
        }
        Ok(added)
    }

    /// Removes tooth `fdi` of `modality`; `MissingData` if it is not held.
    pub fn remove_tooth(&mut self, modality: Modality, fdi: i32) -> Result<Tooth> {
        self.tooth(modality, fdi)?;
        let key = check_fdi(fdi)?;
        self.drop_results();
        self.teeth_mut(modality)
            .remove(&key)
            .ok_or_else(|| Error::MissingData(format!("no {modality} tooth {fdi}")))
    }

    /// Removes every tooth of both modalities (and the results).
    pub fn clear(&mut self) {
        self.ios.clear();
        self.cbct.clear();
        self.drop_results();
    }

    fn drop_results(&mut self) {
        self.registration = None;
        self.cut = None;
        self.fused = None;
        self.notes = Notes::default();
    }

    /// Warnings and skipped teeth of the last result (empty when there is none).
    pub fn notes(&self) -> &Notes {
        &self.notes
    }

    /// The held meshes of `modality` by FDI number.
    fn meshes(&self, modality: Modality) -> BTreeMap<u8, TriMesh> {
        self.teeth(modality)
            .iter()
            .map(|(&f, t)| (f, t.mesh.clone()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ErrorKind;
    use crate::mesh::fixtures::{cube, square, tetrahedron};
    use glam::DVec3;

    #[test]
    fn cbct_needs_closed_ios_may_be_open() {
        let mut s = Session::new();
        s.add_tooth(Modality::Cbct, 11, cube(8.0)).unwrap();
        let e = s.add_tooth(Modality::Cbct, 12, square()).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::NotManifold);
        assert!(
            e.to_string().starts_with("tooth 12: mesh is not closed"),
            "{e}"
        );
        s.add_tooth(Modality::Ios, 12, square()).unwrap();
        assert_eq!(s.fdis(Modality::Cbct), vec![11]);
        assert_eq!(s.fdis(Modality::Ios), vec![12]);
        assert_eq!(s.tooth(Modality::Ios, 12).unwrap().report.boundary_loops, 1);
    }

    #[test]
    fn replace_and_failed_replace_keep_state() {
        let mut s = Session::new();
        s.add_tooth(Modality::Cbct, 21, cube(1.0)).unwrap();
        s.add_tooth(Modality::Cbct, 21, tetrahedron()).unwrap();
        assert_eq!(s.tooth(Modality::Cbct, 21).unwrap().mesh, tetrahedron());
        let mut bad = cube(1.0);
        bad.positions[3].x = f64::NAN;
        let e = s.add_tooth(Modality::Cbct, 21, bad).unwrap_err();
        assert_eq!(
            e.to_string(),
            "tooth 21: vertex 3 has a non-finite coordinate (NaN or infinity)"
        );
        assert_eq!(s.tooth(Modality::Cbct, 21).unwrap().mesh, tetrahedron());
        let e = s.add_tooth(Modality::Cbct, 19, cube(1.0)).unwrap_err();
        assert!(e.to_string().contains("19 is not an FDI"), "{e}");
        let e = s.tooth(Modality::Ios, 21).unwrap_err();
        assert_eq!(
            e.to_string(),
            "missing data: no IOS tooth 21 in the session (IOS teeth held: none)"
        );
        s.remove_tooth(Modality::Cbct, 21).unwrap();
        assert!(s.fdis(Modality::Cbct).is_empty());
    }

    #[test]
    fn ios_repair_resolves_a_bow_tie_and_keeps_positions() {
        // Two triangles touching at vertex 0 only: a bow tie, rejected as is.
        let bow = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y],
            vec![[0, 1, 2], [0, 3, 4]],
        );
        let mut s = Session::new();
        let e = s.add_tooth(Modality::Ios, 11, bow.clone()).unwrap_err();
        // Refused as given, with how to have it repaired; still a manifold error.
        let m = e.to_string();
        assert!(
            m.starts_with("tooth 11: vertex 0 is non-manifold: it joins separate fans of faces; "),
            "{m}"
        );
        assert!(
            m.contains("turn the IOS repair on") && m.contains("ios_repair=True"),
            "{m}"
        );
        assert_eq!(e.kind(), crate::ErrorKind::NotManifold);
        // Naming the tooth again changes nothing: the tooth first, the remedy last.
        assert_eq!(e.clone().in_tooth(11), e);
        // A CBCT tooth is never repaired: no such remedy.
        let e = s.add_tooth(Modality::Cbct, 11, bow.clone()).unwrap_err();
        assert!(!e.to_string().contains("IOS repair"), "{e}");
        s.set_ios_repair(Some(RepairOptions::default())).unwrap();
        s.add_tooth(Modality::Ios, 11, bow.clone()).unwrap();
        let t = s.tooth(Modality::Ios, 11).unwrap();
        let rep = t.repair.clone().unwrap();
        assert!(t.report.non_manifold_vertices == 0 && t.report.non_manifold_edges == 0);
        for (i, &src) in t.source_vertex.iter().enumerate() {
            assert_ne!(src, NO_SOURCE);
            assert_eq!(t.mesh.positions[i], bow.positions[src as usize]);
        }
        // The two fans are separate components: the later one is dropped as an island.
        assert_eq!(rep.island_faces, 1, "{rep:?}");
        assert_eq!(t.mesh.triangles, vec![[0, 1, 2]]);
        // CBCT teeth are never repaired.
        s.add_tooth(Modality::Cbct, 11, cube(1.0)).unwrap();
        assert_eq!(s.tooth(Modality::Cbct, 11).unwrap().repair, None);
        assert!(
            s.set_ios_repair(Some(RepairOptions {
                max_hole_fraction: f64::NAN
            }))
            .is_err()
        );
        assert!(s.ios_repair().is_some());
    }

    /// Two 8 mm cubes (teeth 31, 32) and a square of gingiva in one mesh.
    fn jaw() -> (TriMesh, Vec<i32>) {
        let mut m = cube(8.0);
        let mut c2 = cube(8.0);
        c2.transform(&crate::Rigid::from_translation(DVec3::new(10.0, 0.0, 0.0)));
        m.append(&c2);
        let mut g = square();
        g.transform(&crate::Rigid::from_translation(DVec3::new(0.0, 0.0, -2.0)));
        m.append(&g);
        let mut labels = vec![31; 12];
        labels.extend(vec![32; 12]);
        labels.extend(vec![0; 2]);
        (m, labels)
    }

    #[test]
    fn jaw_split_drops_gingiva_and_maps_vertices() {
        let (m, labels) = jaw();
        let mut s = Session::new();
        assert_eq!(
            s.add_jaw(Modality::Cbct, &m, &labels, LabelDomain::Face)
                .unwrap(),
            vec![31, 32]
        );
        let t = s.tooth(Modality::Cbct, 32).unwrap();
        assert_eq!(t.mesh.triangles.len(), 12);
        for (i, &src) in t.source_vertex.iter().enumerate() {
            assert_eq!(t.mesh.positions[i], m.positions[src as usize]);
            assert!((8..16).contains(&src));
        }
    }

    #[test]
    fn jaw_is_all_or_nothing() {
        let (m, mut labels) = jaw();
        let mut s = Session::new();
        s.add_tooth(Modality::Cbct, 31, tetrahedron()).unwrap();
        // Tooth 32 loses a face: not closed; nothing changes, 31 stays the tetrahedron.
        labels[12] = 0;
        let e = s
            .add_jaw(Modality::Cbct, &m, &labels, LabelDomain::Face)
            .unwrap_err();
        assert!(
            e.to_string().starts_with("tooth 32: mesh is not closed"),
            "{e}"
        );
        assert_eq!(s.tooth(Modality::Cbct, 31).unwrap().mesh, tetrahedron());
        assert_eq!(s.fdis(Modality::Cbct), vec![31]);
        labels[12] = 19;
        let e = s
            .add_jaw(Modality::Cbct, &m, &labels, LabelDomain::Face)
            .unwrap_err();
        assert!(e.to_string().contains("label 19 (on face 12)"), "{e}");
        let e = s
            .add_jaw(Modality::Cbct, &m, &labels[1..], LabelDomain::Face)
            .unwrap_err();
        assert!(e.to_string().contains("25 labels given"), "{e}");
        let e = s
            .add_jaw(Modality::Cbct, &m, &[0; 26], LabelDomain::Face)
            .unwrap_err();
        assert_eq!(e.kind(), ErrorKind::MissingData);
        assert_eq!(s.fdis(Modality::Cbct), vec![31]);
    }
}
