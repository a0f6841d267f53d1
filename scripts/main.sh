#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job: install what is needed, build, render a sky HDRI from the default preset to
# out/welkin_sky.exr, and package the Blender add-on both ways, into dist/:
#   dist/welkin-<version>-linux_x64.zip  the Extension, for Blender 4.2 and later (what most
#                                        artists install), with the compiled core as
#                                        repaired wheels for Python 3.11 and 3.13;
#   dist/welkin-<version>.zip            the legacy add-on zip, for Blender 3.4 (Debian's).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install_deps.sh
bash scripts/build.sh

mkdir -p out
build/welkin sky -o out/welkin_sky.exr --overwrite
echo "main: sky HDRI written to $(pwd)/out/welkin_sky.exr"
bash scripts/build_addon.sh
# The wheels are rebuilt (incrementally) so that the Extension carries this source's core.
bash scripts/build_wheel.sh dist
version=$(sed -n 's/^project(welkin VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
WELKIN_WHEELS="$(echo dist/welkin-"$version"-cp311-*manylinux*.whl dist/welkin-"$version"-cp313-*manylinux*.whl)" \
  bash scripts/build_extension.sh dist
echo "main: packages: $(pwd)/dist/welkin-$version-linux_x64.zip (Extension, Blender 4.2+)," \
     "$(pwd)/dist/welkin-$version.zip (legacy zip, Blender 3.4)"
