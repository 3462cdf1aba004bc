//! The committed header agrees with the crate: version macros match Cargo.toml and the
//! library's functions, and every exported function is declared (and nothing else).

use std::ffi::CStr;
use std::path::Path;

fn header() -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/toothfuse.h");
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn macro_value(h: &str, name: &str) -> u32 {
    let line = h
        .lines()
        .find(|l| l.starts_with(&format!("#define {name} ")))
        .unwrap_or_else(|| panic!("#define {name} missing from toothfuse.h"));
    line.split_whitespace().nth(2).unwrap().parse().unwrap()
}

#[test]
fn version_macros_match_cargo_and_library() {
    let h = header();
    let cargo = |v: &str| v.parse::<u32>().unwrap();
    assert_eq!(
        macro_value(&h, "TOOTHFUSE_VERSION_MAJOR"),
        cargo(env!("CARGO_PKG_VERSION_MAJOR"))
    );
    assert_eq!(
        macro_value(&h, "TOOTHFUSE_VERSION_MINOR"),
        cargo(env!("CARGO_PKG_VERSION_MINOR"))
    );
    assert_eq!(
        macro_value(&h, "TOOTHFUSE_VERSION_PATCH"),
        cargo(env!("CARGO_PKG_VERSION_PATCH"))
    );
    assert_eq!(
        macro_value(&h, "TOOTHFUSE_ABI_VERSION"),
        toothfuse::ffi::toothfuse_abi_version()
    );
    // SAFETY: static NUL-terminated string.
    let v = unsafe { CStr::from_ptr(toothfuse::ffi::toothfuse_version()) };
    let want = format!(
        "{}.{}.{}",
        macro_value(&h, "TOOTHFUSE_VERSION_MAJOR"),
        macro_value(&h, "TOOTHFUSE_VERSION_MINOR"),
        macro_value(&h, "TOOTHFUSE_VERSION_PATCH")
    );
    assert_eq!(v.to_str().unwrap(), want);
}

/// Names `toothfuse_*` followed by `(` in `text`, sorted and deduplicated.
fn called_names(text: &str, prefix: &str) -> Vec<String> {
    let mut out: Vec<String> = text
        .match_indices(prefix)
        .filter_map(|(i, _)| {
            let rest = &text[i..];
            let end = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))?;
            rest[end..]
                .starts_with('(')
                .then(|| rest[..end].to_string())
        })
        .collect();
    out.sort();
    out.dedup();
    out
}

#[test]
fn header_declares_exactly_the_exported_functions() {
    let h = header();
    let declared = called_names(&h, "toothfuse_");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/ffi");
    let mut exported = Vec::new();
    for e in std::fs::read_dir(&dir).unwrap() {
        let src = std::fs::read_to_string(e.unwrap().path()).unwrap();
        let mut lines = src.lines();
        while let Some(l) = lines.next() {
            if l.trim() == "#[unsafe(no_mangle)]" {
                let sig = lines.next().unwrap();
                let name = sig.split("fn ").nth(1).unwrap().split('(').next().unwrap();
                exported.push(name.to_string());
            }
        }
    }
    exported.sort();
    assert!(
        exported.iter().all(|n| n.starts_with("toothfuse_")),
        "{exported:?}"
    );
    // The header mentions only declared functions followed by '(' (docs use backticks
    // without parentheses except `toothfuse_abi_version()`, itself exported).
    assert_eq!(declared, exported);
}
