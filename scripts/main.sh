#!/usr/bin/env bash
# The main job: install what is needed, build, and render a sky HDRI from the default
# preset to out/welkin_sky.exr, and package the Blender add-on as dist/welkin-<version>.zip.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install_deps.sh
bash scripts/build.sh

mkdir -p out
build/welkin sky -o out/welkin_sky.exr --overwrite
echo "main: sky HDRI written to $(pwd)/out/welkin_sky.exr"
bash scripts/build_addon.sh
