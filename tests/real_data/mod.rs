//! The shared real data (`../shared/data/real` or `TOOTHFUSE_REAL_DATA`) for the tests that read
//! it in place: a file there, or `None` after saying on stderr why the test is skipped.

use std::path::PathBuf;

/// `rel` under the real data folder, or `None` (with a SKIPPED message) when it is absent.
pub fn real(rel: &str) -> Option<PathBuf> {
    let Some(dir) = toothfuse::io::real_data_dir() else {
        eprintln!(
            "SKIPPED: real data folder not found (set TOOTHFUSE_REAL_DATA or provide ../shared/data/real)"
        );
        return None;
    };
    let p = dir.join(rel);
    if !p.exists() {
        eprintln!("SKIPPED: {} not found", p.display());
        return None;
    }
    Some(p)
}
