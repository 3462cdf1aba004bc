//! Fuzzes `toothfuse::io::read_obj_labeled_bytes`: the input is an OBJ, optionally followed by a
//! NUL byte and its Teeth3DS label JSON. A mesh or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (obj, json) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(("fuzz.json", &data[i + 1..]))),
        None => (data, None),
    };
    if let Ok(m) = toothfuse::io::read_obj_labeled_bytes("fuzz.obj", obj, json) {
        toothfuse_fuzz::check_read(&m);
        if json.is_some() {
            assert!(m.vertex_labels.is_some(), "labels read but not returned");
        }
    }
});
