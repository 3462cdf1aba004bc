#!/usr/bin/env bash
# THE test command: installs what is missing, then runs every check and test.
#   bash scripts/test.sh
# On a fresh Debian machine it installs (apt-get) cmake, pkg-config, g++, libvtk9-dev,
# libopenmesh-dev, libgtest-dev, and cbindgen 0.29.0 (cargo), plus rustfmt/clippy (rustup).
# Then: cargo fmt --check, cargo clippy -D warnings, cargo doc -D warnings, cargo test --release (library, CLI and
# integration tests; the test executables run side by side by scripts/run_test_binaries.py), the header check,
# the exported-symbols check, the CMake build + install into build/prefix, ctest (C/C++/Python
# tests against the installed package), an outside find_package consumer, a pkg-config build, and
# the Python package: pip install ./bindings/python into a fresh venv (numpy and pytest from PyPI;
# the library is the one cargo already built in target/) and its pytest suite run there;
# then scripts/check_sanitizers.sh (C/C++ tests under ASan+UBSan, valgrind memcheck, Miri over
# the C-ABI unit tests) and scripts/check_fuzz.sh (every cargo-fuzz target for 20 s, nightly only).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)
BUILD="$ROOT/build"
PREFIX="$BUILD/prefix"
CBINDGEN_VERSION=0.29.0
JOBS=$(nproc 2>/dev/null || echo 2)
START=$(date +%s)

# The test executables, the CLI runs they start and the C/C++ tests share the phantom jaws they
# generate through this cache (`Phantom::generate`, keyed by the options and the library's
# source): each jaw is made once per run. Emptied here, removed at the end.
export TOOTHFUSE_PHANTOM_CACHE="$BUILD/phantom-cache"
rm -rf "$TOOTHFUSE_PHANTOM_CACHE"

section() { printf '\n==== %s ==== (%ss)\n' "$*" "$(($(date +%s) - START))"; }

# ---------------------------------------------------------------------------------------------
section "dependencies"
sudo_if_needed() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
missing=()
command -v cmake >/dev/null || missing+=(cmake)
command -v pkg-config >/dev/null || missing+=(pkg-config)
command -v g++ >/dev/null || missing+=(g++)
[ -e /usr/include/vtk-9.1/vtkPLYReader.h ] || ls /usr/include/vtk-9*/vtkPLYReader.h >/dev/null 2>&1 \
  || missing+=(libvtk9-dev)
[ -e /usr/include/OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh ] || missing+=(libopenmesh-dev)
[ -e /usr/include/gtest/gtest.h ] || missing+=(libgtest-dev)
command -v python3 >/dev/null || missing+=(python3)
python3 -c 'import ensurepip, venv' 2>/dev/null || missing+=(python3-venv)
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  sudo_if_needed apt-get update
  DEBIAN_FRONTEND=noninteractive sudo_if_needed apt-get install -y --no-install-recommends \
    "${missing[@]}"
else
  echo "system packages present"
fi
if ! cargo fmt --version >/dev/null 2>&1; then rustup component add rustfmt; fi
if ! cargo clippy --version >/dev/null 2>&1; then rustup component add clippy; fi
if [ "$(cbindgen --version 2>/dev/null || true)" != "cbindgen $CBINDGEN_VERSION" ]; then
  cargo install cbindgen --version "$CBINDGEN_VERSION" --locked --force
fi

# ---------------------------------------------------------------------------------------------
section "cargo fmt --check"
cargo fmt --check

# Clippy and rustdoc in the release profile: their build scripts and proc macros are then the
# ones the release build below uses (built once on a fresh machine, not once per profile).
section "cargo clippy --release --workspace --all-targets -- -D warnings (library, CLI, tests, examples, benches)"
cargo clippy --release --workspace --all-targets -- -D warnings

section "cargo doc --release --no-deps --lib with warnings denied (broken or ambiguous doc links)"
RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps --lib

section "cargo test --release --lib --bins --tests (test executables run $JOBS at a time)"
# The library's unit tests, the CLI's and every integration test; the examples and benches are
# compiled (checked) by clippy above and not built again here. scripts/run_test_binaries.py
# builds them as `cargo test` does and runs the executables side by side, longest first (cargo
# test runs one executable after the other and a core stays idle during the long ones).
python3 scripts/run_test_binaries.py --jobs "$JOBS" -- --release --lib --bins --tests

# ---------------------------------------------------------------------------------------------
section "header check (include/toothfuse.h is what cbindgen $CBINDGEN_VERSION generates)"
fresh=$(mktemp)
trap 'rm -f "$fresh"' EXIT
cbindgen --quiet --config cbindgen.toml --crate toothfuse --output "$fresh"
if ! diff -u include/toothfuse.h "$fresh"; then
  echo "include/toothfuse.h is stale: regenerate with" >&2
  echo "  cbindgen --config cbindgen.toml --crate toothfuse --output include/toothfuse.h" >&2
  exit 1
fi
echo "header up to date"

# ---------------------------------------------------------------------------------------------
section "CMake build + install into $PREFIX"
cmake -S . -B "$BUILD/lib" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$PREFIX" >/dev/null
cmake --build "$BUILD/lib" -j "$JOBS"
rm -rf "$PREFIX"
cmake --install "$BUILD/lib"

section "exported symbols of libtoothfuse.so are toothfuse_* only"
so="$PREFIX/lib/libtoothfuse.so"
readelf -d "$so" | grep -q 'SONAME.*libtoothfuse\.so\.0' || { echo "bad SONAME" >&2; exit 1; }
syms=$(nm -D --defined-only "$so" | awk '{print $3}')
bad=$(echo "$syms" | grep -v '^toothfuse_' || true)
if [ -n "$bad" ]; then
  echo "unexpected exported symbols:" >&2
  echo "$bad" >&2
  exit 1
fi
echo "$(echo "$syms" | wc -l) symbols, all toothfuse_*"

# ---------------------------------------------------------------------------------------------
section "C/C++/Python tests (ctest) against the installed package"
cmake -S cpp_tests -B "$BUILD/cpp_tests" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_PREFIX_PATH="$PREFIX" ${TOOTHFUSE_REAL_DATA:+-DTOOTHFUSE_REAL_DATA="$TOOTHFUSE_REAL_DATA"} \
  >/dev/null
cmake --build "$BUILD/cpp_tests" -j "$JOBS"
(cd "$BUILD/cpp_tests" && ctest --output-on-failure -j "$JOBS")

section "outside consumer (find_package(toothfuse CONFIG REQUIRED))"
cmake -S cpp_tests/consumer -B "$BUILD/consumer" -DCMAKE_PREFIX_PATH="$PREFIX" >/dev/null
cmake --build "$BUILD/consumer" -j "$JOBS"
(cd "$BUILD/consumer" && ctest --output-on-failure)

section "pkg-config consumer"
export PKG_CONFIG_PATH="$PREFIX/lib/pkgconfig"
pkg-config --exists --print-errors toothfuse
test "$(pkg-config --modversion toothfuse)" = "$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)"
cc -std=c11 -Wall -Wextra -Wpedantic -Werror $(pkg-config --cflags toothfuse) \
  cpp_tests/consumer/main.c -o "$BUILD/pkgconfig_consumer" $(pkg-config --libs toothfuse) \
  -Wl,-rpath,"$PREFIX/lib"
"$BUILD/pkgconfig_consumer"
cc -std=c11 $(pkg-config --cflags toothfuse) cpp_tests/consumer/main.c \
  -o "$BUILD/pkgconfig_consumer_static" "$PREFIX/lib/libtoothfuse.a" \
  $(pkg-config --libs-only-l --static toothfuse | sed 's/-ltoothfuse//')
"$BUILD/pkgconfig_consumer_static"

# ---------------------------------------------------------------------------------------------
section "Python package: pip install ./bindings/python into a fresh venv, import, pytest there"
VENV="$BUILD/pyvenv"
rm -rf "$VENV"
python3 -m venv "$VENV"
# From another directory, so that `import toothfuse` can only find the installed package. The
# build reuses target/ (CARGO_TARGET_DIR is honoured): cargo only confirms the library is fresh.
(cd "$BUILD" && "$VENV/bin/pip" install --quiet --disable-pip-version-check \
  "$ROOT/bindings/python" pytest)
(cd "$BUILD" && "$VENV/bin/python" -c \
  'import toothfuse; print("toothfuse", toothfuse.version(), "from", toothfuse.__file__)')
(cd "$BUILD" && TOOTHFUSE_JAWS_DIR="$BUILD/cpp_tests/jaws" \
  "$VENV/bin/python" -m pytest -q "$ROOT/bindings/python/tests")

section "sanitizers: ASan+UBSan C/C++ tests, valgrind memcheck, Miri (scripts/check_sanitizers.sh)"
bash scripts/check_sanitizers.sh "$PREFIX" "$BUILD/cpp_tests"

section "fuzzing: each cargo-fuzz target ${FUZZ_SECONDS:-20} s (scripts/check_fuzz.sh)"
bash scripts/check_fuzz.sh

rm -rf "$TOOTHFUSE_PHANTOM_CACHE"
section "all tests passed in $(($(date +%s) - START)) s"
