"""Builds the toothfuse Rust library with cargo and puts libtoothfuse.so into the package.

The crate root is found by walking up from this file to the Cargo.toml of the `toothfuse`
crate (pip >= 21.3 builds a local directory in place, so ../../Cargo.toml is reachable), or
taken from TOOTHFUSE_CRATE_DIR. cargo runs `build --release --lib` with the target directory
CARGO_TARGET_DIR or <crate>/target, so an already built tree is reused; CARGO (default `cargo`)
names the cargo executable.
"""

import os
import shutil
import subprocess
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py


def crate_root() -> Path:
    env = os.environ.get("TOOTHFUSE_CRATE_DIR")
    if env:
        return Path(env).resolve()
    here = Path(__file__).resolve().parent
    for d in [here, *here.parents]:
        manifest = d / "Cargo.toml"
        if manifest.is_file() and 'name = "toothfuse"' in manifest.read_text():
            return d
    raise SystemExit(
        f"toothfuse: no toothfuse Cargo.toml above {here}; build from the repository "
        "(pip install ./bindings/python) or set TOOTHFUSE_CRATE_DIR")


def cargo_executable() -> str:
    cargo = os.environ.get("CARGO") or shutil.which("cargo")
    if not cargo and (Path.home() / ".cargo/bin/cargo").exists():
        cargo = str(Path.home() / ".cargo/bin/cargo")
    if not cargo:
        raise SystemExit("toothfuse: cargo not found (install Rust, or set CARGO)")
    return cargo


class BuildWithLibrary(build_py):
    """build_py that also compiles the Rust library and copies it into the package."""

    def run(self):
        super().run()
        root = crate_root()
        target = Path(os.environ.get("CARGO_TARGET_DIR") or root / "target")
        subprocess.run(
            [cargo_executable(), "build", "--release", "--lib",
             "--manifest-path", str(root / "Cargo.toml"), "--target-dir", str(target)],
            check=True)
        dest = Path(self.build_lib) / "toothfuse"
        dest.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(target / "release" / "libtoothfuse.so", dest / "libtoothfuse.so")


class BinaryDistribution(Distribution):
    """The wheel holds a native library: platform-specific, not pure Python."""

    def has_ext_modules(self):
        return True


setup(cmdclass={"build_py": BuildWithLibrary}, distclass=BinaryDistribution)
