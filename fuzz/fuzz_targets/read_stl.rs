//! Fuzzes `toothfuse::io::read_stl_bytes` (binary and ASCII): a mesh or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use toothfuse::mesh::LabeledMesh;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = toothfuse::io::read_stl_bytes("fuzz.stl", data) {
        toothfuse_fuzz::check_read(&LabeledMesh {
            mesh,
            ..Default::default()
        });
    }
});
