#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs the Debian 12 packages Welkin needs to build, test and render (xvfb: the
# viewport preview's windowed Blender test, tests/blender/test_viewport_window.py; clang
# and its runtime: the fuzz targets, scripts/fuzz.sh; munge and slurm-wlm: the Slurm farm
# test, tests/farm/test_slurm.sh, which starts its own daemons).
# Idempotent and quick when everything is there: it asks dpkg first, and runs
# apt-get (update + install, non-interactively) only for what is missing.
set -euo pipefail

packages=(
  cmake g++ make pkg-config ccache clang-format
  libglm-dev libtbb-dev libopenexr-dev libopenvdb-dev libboost-iostreams-dev liberfa-dev
  clang libclang-rt-14-dev
  pybind11-dev nlohmann-json3-dev libcli11-dev libfmt-dev libspdlog-dev libgtest-dev
  python3-dev python3-numpy python3-pytest python3-matplotlib python3-openvdb python3-skimage
  blender
  xvfb xauth
  munge slurm-wlm
)

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
  [[ "$status" == installed ]] || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  echo "install_deps: all ${#packages[@]} packages are installed"
  exit 0
fi

echo "install_deps: installing ${missing[*]}"
if [[ $(id -u) -eq 0 ]]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
else
  echo "install_deps: missing packages (${missing[*]}) and neither root nor sudo;" \
       "install them and run again" >&2
  exit 1
fi

"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
  apt-get install -y -q --no-install-recommends "${missing[@]}"
