//! Fuzzes `toothfuse::io::read_ply_bytes`: any input is a mesh or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = toothfuse::io::read_ply_bytes("fuzz", data) {
        toothfuse_fuzz::check_read(&m);
    }
});
