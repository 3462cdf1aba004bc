//! Helpers shared by the C ABI tests: tiny meshes and a session wrapper that calls the ABI as a
//! C caller would.
#![allow(dead_code)]

use std::ffi::CStr;
use std::ptr;
use toothfuse::ffi::*;

/// An axis-aligned cube [0,s]^3 offset by `o`: 8 vertices, 12 outward triangles.
pub fn cube(s: f64, o: [f64; 3]) -> (Vec<f64>, Vec<u32>) {
    let mut v = Vec::new();
    for (x, y, z) in [
        (0., 0., 0.),
        (1., 0., 0.),
        (1., 1., 0.),
        (0., 1., 0.),
        (0., 0., 1.),
        (1., 0., 1.),
        (1., 1., 1.),
        (0., 1., 1.),
    ] {
        v.extend([o[0] + x * s, o[1] + y * s, o[2] + z * s]);
    }
    let t = vec![
        0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6,
        3, 0, 4, 3, 4, 7,
    ];
    (v, t)
}

/// An open square (2 triangles): a valid IOS crown, an invalid CBCT tooth.
pub fn square() -> (Vec<f64>, Vec<u32>) {
    (
        vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.],
        vec![0, 1, 2, 0, 2, 3],
    )
}

pub struct Session(pub *mut toothfuse_session);

impl Session {
    pub fn new() -> Self {
        let mut p = ptr::null_mut();
        // SAFETY: valid out pointer.
        let st = unsafe { toothfuse_session_new(&mut p) };
        assert_eq!(st, toothfuse_status::Ok);
        assert!(!p.is_null());
        Session(p)
    }
    pub fn error(&self) -> String {
        // SAFETY: live session; the string is copied before the next call.
        unsafe { CStr::from_ptr(toothfuse_session_last_error(self.0)) }
            .to_str()
            .unwrap()
            .to_owned()
    }
    pub fn add(&self, m: toothfuse_modality, fdi: i32, v: &[f64], t: &[u32]) -> toothfuse_status {
        // SAFETY: buffers sized as announced.
        unsafe {
            toothfuse_session_add_tooth(
                self.0,
                m,
                fdi,
                v.as_ptr().cast(),
                v.len() / 3,
                24,
                TOOTHFUSE_SCALAR_FLOAT64,
                t.as_ptr(),
                t.len(),
            )
        }
    }
    pub fn teeth(&self, m: toothfuse_modality) -> Vec<i32> {
        let mut n = 0usize;
        // SAFETY: live session, valid out pointers.
        unsafe {
            assert_eq!(
                toothfuse_session_tooth_count(self.0, m, &mut n),
                toothfuse_status::Ok
            );
            let mut out = vec![0i32; n];
            let mut written = 0usize;
            assert_eq!(
                toothfuse_session_list_teeth(self.0, m, out.as_mut_ptr(), n, &mut written),
                toothfuse_status::Ok
            );
            assert_eq!(written, n);
            out
        }
    }
    pub fn positions(&self, m: toothfuse_modality, fdi: i32) -> Vec<f64> {
        let (mut nv, mut ni) = (0usize, 0usize);
        // SAFETY: live session, buffers sized from the size query.
        unsafe {
            assert_eq!(
                toothfuse_session_mesh_size(self.0, m, fdi, &mut nv, &mut ni),
                toothfuse_status::Ok
            );
            let mut out = vec![0f64; 3 * nv];
            assert_eq!(
                toothfuse_session_copy_vertices(
                    self.0,
                    m,
                    fdi,
                    out.as_mut_ptr().cast(),
                    nv,
                    24,
                    TOOTHFUSE_SCALAR_FLOAT64
                ),
                toothfuse_status::Ok
            );
            out
        }
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        // SAFETY: created by toothfuse_session_new, freed once.
        unsafe { toothfuse_session_free(self.0) };
    }
}

/// A small synthetic jaw (partial arch: 3–5 teeth, fast) for registration and fusion tests.
pub fn phantom(seed: u64) -> toothfuse::phantom::Phantom {
    use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
    Phantom::generate(&PhantomOptions {
        seed,
        variant: Variant::PartialArch,
        ..PhantomOptions::default()
    })
    .expect("phantom")
}

/// Feeds a phantom through the ABI: the labeled IOS jaw with `add_jaw`, each CBCT tooth with
/// `add_tooth`.
pub fn add_phantom(s: &Session, p: &toothfuse::phantom::Phantom) {
    let v: Vec<f64> = p
        .ios
        .mesh
        .positions
        .iter()
        .flat_map(|q| q.to_array())
        .collect();
    let t: Vec<u32> = p.ios.mesh.triangles.iter().flatten().copied().collect();
    let labels = p.ios.vertex_labels.as_ref().expect("vertex labels");
    // SAFETY: buffers sized as announced.
    let st = unsafe {
        toothfuse_session_add_jaw(
            s.0,
            TOOTHFUSE_MODALITY_IOS,
            v.as_ptr().cast(),
            v.len() / 3,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            t.as_ptr(),
            t.len(),
            labels.as_ptr(),
            labels.len(),
            TOOTHFUSE_LABEL_DOMAIN_VERTEX,
        )
    };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    for (&fdi, m) in &p.cbct {
        let v: Vec<f64> = m.positions.iter().flat_map(|q| q.to_array()).collect();
        let t: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let st = s.add(TOOTHFUSE_MODALITY_CBCT, i32::from(fdi), &v, &t);
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    }
}

/// Runs the one-call fuse on `s` with the default options and asserts that it succeeded.
pub fn fuse_default(s: &Session) {
    // SAFETY: live session, NULL options = defaults.
    let st = unsafe { toothfuse_session_fuse(s.0, ptr::null()) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
}

/// Positions (x, y, z per vertex) and indices of fused mesh `fdi` (0: the whole jaw) by the
/// size query and copy-out.
pub fn fused_copy(s: &Session, fdi: i32) -> (Vec<f64>, Vec<u32>) {
    let (mut nv, mut ni) = (0usize, 0usize);
    // SAFETY: live session; buffers sized from the size query.
    unsafe {
        let st = toothfuse_session_fused_size(s.0, fdi, &mut nv, &mut ni);
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
        let mut v = vec![0f64; 3 * nv];
        let mut t = vec![0u32; ni];
        let (vp, tp) = (v.as_mut_ptr().cast(), t.as_mut_ptr());
        let st =
            toothfuse_session_copy_fused_vertices(s.0, fdi, vp, nv, 24, TOOTHFUSE_SCALAR_FLOAT64);
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
        let st = toothfuse_session_copy_fused_indices(s.0, fdi, tp, ni);
        assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
        (v, t)
    }
}

/// The report JSON of the last fuse (size query, then copy).
pub fn report_json(s: &Session) -> String {
    let mut len = 0usize;
    // SAFETY: live session; size query then copy.
    unsafe {
        assert_eq!(
            toothfuse_session_report_json(s.0, ptr::null_mut(), 0, &mut len),
            toothfuse_status::Ok
        );
        let mut buf = vec![0 as std::ffi::c_char; len + 1];
        assert_eq!(
            toothfuse_session_report_json(s.0, buf.as_mut_ptr(), len + 1, &mut len),
            toothfuse_status::Ok
        );
        CStr::from_ptr(buf.as_ptr()).to_str().unwrap().to_owned()
    }
}
