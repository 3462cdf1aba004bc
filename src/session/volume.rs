//! Adding the CBCT teeth of a label volume to a session: every tooth label surfaced (see
//! [`crate::volume::surface`]) and added as a CBCT tooth, all or nothing. A per-jaw volume
//! (DentalSegmentator classes) is first split into teeth with the IOS crowns the session holds
//! ([`crate::volume::split`]); the split per tooth is kept and added to the result notes.

use super::{Modality, Session, Tooth};
use crate::volume::{
    LabelVolume, SplitOptions, SurfaceOptions, SurfacedTeeth, VolumeScheme, split_teeth,
    surface_teeth,
};
use crate::{Error, Result, TriMesh};
use std::collections::BTreeMap;

impl Session {
    /// Surfaces every tooth label of `vol` (numbered by `scheme`) and adds each as a CBCT
    /// tooth in the volume's world frame, replacing CBCT teeth of the same FDI numbers. All or
    /// nothing: on any error (unknown label, no tooth label, a per-jaw volume, a surface that
    /// fails validation) the session is unchanged. Returns what was surfaced and skipped (the
    /// meshes are moved into the session, so the returned teeth have empty meshes).
    ///
    /// With [`VolumeScheme::DentalSegmentator`] the teeth classes are split with the IOS crowns
    /// already added (add the IOS first); teeth whose split is refused are listed as skipped
    /// with the reason, and each tooth's split (its contested share, or why it was refused) is
    /// added to the notes of later results ([`Session::notes`]) until the next label volume.
    pub fn add_label_volume(
        &mut self,
        vol: &LabelVolume,
        scheme: VolumeScheme,
        opts: &SurfaceOptions,
    ) -> Result<SurfacedTeeth> {
        let (mut surfaced, split_notes) = if scheme == VolumeScheme::DentalSegmentator {
            self.split_and_surface(vol, opts)?
        } else {
            (surface_teeth(vol, scheme, opts)?, BTreeMap::new())
        };
        let mut staged: Vec<Tooth> = Vec::new();
        for (&fdi, tooth) in &mut surfaced.teeth {
            let mesh = std::mem::take(&mut tooth.mesh);
            let source = (0..mesh.positions.len() as u32).collect();
            staged.push(self.prepare(Modality::Cbct, fdi, mesh, source)?);
        }
        self.drop_results();
        let teeth = self.teeth_mut(Modality::Cbct);
        for t in staged {
            teeth.insert(t.fdi, t);
        }
        self.split_notes = split_notes;
        Ok(surfaced)
    }

    /// The teeth of a per-jaw volume split with the held IOS crowns, surfaced; and the split
    /// per tooth.
    fn split_and_surface(
        &self,
        vol: &LabelVolume,
        opts: &SurfaceOptions,
    ) -> Result<(SurfacedTeeth, BTreeMap<u8, String>)> {
        let crowns: BTreeMap<u8, TriMesh> = self
            .teeth(Modality::Ios)
            .iter()
            .map(|(f, t)| (*f, t.mesh.clone()))
            .collect();
        if crowns.is_empty() {
            return Err(Error::MissingData(
                "a per-jaw teeth volume (DentalSegmentator classes) is split into teeth with the \
                 IOS crowns: add the IOS teeth first"
                    .into(),
            ));
        }
        let split = split_teeth(vol, &crowns, &SplitOptions::default())?;
        crate::progress::check(crate::progress::Stage::Surface)?;
        let mut surfaced = surface_teeth(&split.volume, VolumeScheme::Fdi, opts)?;
        let mut notes = BTreeMap::new();
        for j in &split.jaws {
            for (fdi, t) in &j.teeth {
                let line = match j.refused.get(fdi) {
                    Some(r) => {
                        surfaced
                            .skipped
                            .push((*fdi as u16, format!("split refused: {r}")));
                        format!("CBCT split from the per-jaw teeth mask refused: {r}")
                    }
                    None => format!(
                        "CBCT tooth split from the per-jaw teeth mask: {:.1}% of its voxels \
                         contested, {:.1}% beyond the narrowest cut to a neighbour ({:.1}% of \
                         its flood's handed over to a neighbour beyond it)",
                        100.0 * t.contested_share(),
                        100.0 * t.overrun_share(),
                        100.0 * t.handed_over_share()
                    ),
                };
                notes.insert(*fdi, line);
            }
        }
        Ok((surfaced, notes))
    }

    /// Adds the split notes of the last label volume to the result notes: a warning for each
    /// registered tooth, the reason appended for a skipped one.
    pub(super) fn add_split_notes(&mut self) {
        for (fdi, line) in &self.split_notes {
            let c = super::results::c_string(line);
            if let Some(w) = self.notes.warnings.get_mut(fdi) {
                w.push(c);
            } else if let Some(s) = self.notes.skipped.iter_mut().find(|s| s.0 == *fdi) {
                s.1 = super::results::c_string(&format!("{}; {line}", s.1.to_string_lossy()));
            }
        }
    }
}
