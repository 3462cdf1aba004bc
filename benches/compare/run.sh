#!/usr/bin/env bash
# Side by side with Open3D and a paper-style pipeline (README, "Side by side"):
#   bash benches/compare/run.sh
# Creates build/compare-venv (first run: ~600 MB of wheels from PyPI), builds toothfuse and the
# icp_compare example, then runs benches/compare/compare.py, which prints one markdown table and
# writes it to build/compare/results.md. The foreign jaws are read from $TOOTHFUSE_FOREIGN_DATA,
# else from shared/data/foreign beside the checkout. Not part of scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/../.."
# Keeps benches/compare free of __pycache__ folders.
export PYTHONDONTWRITEBYTECODE=1

VENV=build/compare-venv
PY="$VENV/bin/python"
if [ ! -x "$PY" ]; then
    python3 -m venv "$VENV"
fi
# The versions the README's table was measured with.
"$PY" -m pip install --quiet --disable-pip-version-check numpy==2.4.6 scipy==1.17.1 vtk==9.7.2
if ! "$PY" -m pip install --quiet --disable-pip-version-check open3d==0.20.0; then
    echo "open3d 0.20.0 could not be installed for $("$PY" --version): the Open3D side is skipped"
fi
# Open3D's wheel links libusb, which slim Debian images lack.
import_error=$("$PY" -c "import open3d" 2>&1 || true)
if [[ "$import_error" == *libusb-1.0.so* ]]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        apt-get install -y -qq libusb-1.0-0 >/dev/null \
            || { apt-get update -qq && apt-get install -y -qq libusb-1.0-0 >/dev/null; }
    else
        echo "Open3D needs libusb-1.0-0 (apt-get install libusb-1.0-0); the Open3D side is skipped"
    fi
fi

cargo build --release --bin toothfuse --example icp_compare

FOREIGN="${TOOTHFUSE_FOREIGN_DATA:-}"
if [ -z "$FOREIGN" ]; then
    for d in ../shared/data/foreign ../../shared/data/foreign; do
        if [ -d "$d" ]; then FOREIGN="$d"; break; fi
    done
fi
if [ -z "$FOREIGN" ] || [ ! -d "$FOREIGN/f901_upper" ]; then
    echo "foreign jaws not found: set TOOTHFUSE_FOREIGN_DATA to shared/data/foreign" >&2
    exit 1
fi

"$PY" benches/compare/compare.py --foreign "$(cd "$FOREIGN" && pwd)"
