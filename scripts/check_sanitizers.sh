#!/usr/bin/env bash
# Memory and undefined-behaviour checks of the C ABI, called by scripts/test.sh after the
# package is installed and the ctest build exists (it reuses both):
#   bash scripts/check_sanitizers.sh [PREFIX] [CTEST_BUILD_DIR]
# (defaults build/prefix and build/cpp_tests). Three parts:
#  1. AddressSanitizer + UndefinedBehaviorSanitizer: the C11 test (shared and static library) and
#     the C++ suites that need at most the one demo jaw (error paths, registration through VTK
#     floats and OpenMesh doubles, the VTK copy-out round trip), built in build/cpp_tests_asan
#     with -O1 -fsanitize=address,undefined
#     -fno-sanitize-recover=all (any report fails the test; LeakSanitizer on, with the VTK
#     suppressions of cpp_tests/lsan_vtk.supp). The Rust library itself is not instrumented:
#     ASan checks every access the C/C++ callers make into buffers the library fills or
#     borrows, and LeakSanitizer every allocation (Rust's included) left at exit.
#  2. valgrind memcheck on the uninstrumented C11 test (static library) and on the C++ error-path
#     suite: 0 errors, no definite leaks (--error-exitcode=1 --errors-for-leak-kinds=definite).
#  3. Miri over the C-ABI unit tests (src/ffi) when a nightly toolchain is present: undefined
#     behaviour in the unsafe layer itself (pointer reads and writes, strides, alignment, the
#     panic boundary). Tests that cannot run under Miri are #[cfg_attr(miri, ignore)].
# Installs valgrind (apt) and the nightly miri + rust-src components when missing.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)
PREFIX=${1:-$ROOT/build/prefix}
MAIN_TESTS=${2:-$ROOT/build/cpp_tests}
ASAN_BUILD="$ROOT/build/cpp_tests_asan"
JOBS=$(nproc 2>/dev/null || echo 2)
START=$(date +%s)
step() { printf -- '---- %s (%ss)\n' "$*" "$(($(date +%s) - START))"; }
sudo_if_needed() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

# --- 1. ASan + UBSan ------------------------------------------------------------------------
step "ASan + UBSan build of the C and C++ tests ($ASAN_BUILD)"
SAN_FLAGS="-O1 -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
cmake -S cpp_tests -B "$ASAN_BUILD" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_PREFIX_PATH="$PREFIX" \
  -DTOOTHFUSE_SANITIZE_C_TEST=OFF -DCMAKE_C_FLAGS="$SAN_FLAGS" -DCMAKE_CXX_FLAGS="$SAN_FLAGS" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
SAN_TESTS=(c_api_test_shared c_api_test_static error_paths_test register_test vtk_roundtrip_test)
cmake --build "$ASAN_BUILD" -j "$JOBS" --target "${SAN_TESTS[@]}"
step "ASan + UBSan run"
(
  cd "$ASAN_BUILD"
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export LSAN_OPTIONS=suppressions=$ROOT/cpp_tests/lsan_vtk.supp
  ctest --output-on-failure -j "$JOBS" \
    -R '^(c_api_shared|c_api_static|error_paths_test|register_test|vtk_roundtrip_test)$'
)

# --- 2. valgrind memcheck -------------------------------------------------------------------
if ! command -v valgrind >/dev/null; then
  echo "installing valgrind"
  sudo_if_needed apt-get update
  DEBIAN_FRONTEND=noninteractive sudo_if_needed apt-get install -y --no-install-recommends valgrind
fi
VG=(valgrind --quiet --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite
    --show-leak-kinds=definite --track-origins=yes)
step "valgrind memcheck: C11 test (static library)"
"${VG[@]}" "$MAIN_TESTS/c_api_test_static"
step "valgrind memcheck: C++ error paths"
"${VG[@]}" "$MAIN_TESTS/error_paths_test" --gtest_brief=1

# --- 3. Miri over the C-ABI unit tests ------------------------------------------------------
if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
  rustup +nightly component add miri rust-src >/dev/null 2>&1 || true
fi
if cargo +nightly miri --version >/dev/null 2>&1; then
  step "Miri: cargo +nightly miri test --lib --no-default-features ffi::"
  MIRIFLAGS="${MIRIFLAGS:--Zmiri-strict-provenance}" \
    cargo +nightly miri test --lib --no-default-features --target-dir "$ROOT/target/miri-build" -- ffi::
else
  echo "SKIPPED Miri: no nightly toolchain with the miri component (rustup toolchain install nightly --component miri rust-src)"
fi
step "sanitizers, valgrind and Miri passed"
