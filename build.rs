//! Build script: gives the shared library its SONAME (`libtoothfuse.so.<major>`) on Linux so the
//! CMake package can install it with SOVERSION = major.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if os == "linux" {
        let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap_or_else(|_| "0".into());
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libtoothfuse.so.{major}");
    }
}
