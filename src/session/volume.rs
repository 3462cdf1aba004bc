//! Adding the CBCT teeth of a label volume to a session: every tooth label surfaced (see
//! [`crate::volume::surface`]) and added as a CBCT tooth, all or nothing.

use super::{Modality, Session, Tooth};
use crate::Result;
use crate::volume::{LabelVolume, SurfaceOptions, SurfacedTeeth, VolumeScheme, surface_teeth};

impl Session {
    /// Surfaces every tooth label of `vol` (numbered by `scheme`) and adds each as a CBCT
    /// tooth in the volume's world frame, replacing CBCT teeth of the same FDI numbers. All or
    /// nothing: on any error (unknown label, no tooth label, a per-jaw volume, a surface that
    /// fails validation) the session is unchanged. Returns what was surfaced and skipped (the
    /// meshes are moved into the session, so the returned teeth have empty meshes).
    pub fn add_label_volume(
        &mut self,
        vol: &LabelVolume,
        scheme: VolumeScheme,
        opts: &SurfaceOptions,
    ) -> Result<SurfacedTeeth> {
        let mut surfaced = surface_teeth(vol, scheme, opts)?;
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
        Ok(surfaced)
    }
}
