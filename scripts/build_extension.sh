#!/usr/bin/env bash
# Builds the Blender Extension (Blender 4.2 and later): dist/welkin-<version>-linux_x64.zip,
# holding addon/welkin/ with its blender_manifest.toml and, in wheels/, the compiled core
# as the repaired wheel of scripts/build_wheel.sh (Blender installs it into the
# extensions' site-packages). Built and validated with Blender's own extension tooling,
# blender_ext.py from the bpy 4.5 venv (scripts/install_blender_venvs.sh). Install it in
# Blender with Edit > Preferences > Get Extensions > Install from Disk, or headless with
# bpy.ops.extensions.package_install_files(filepath=..., repo="user_default").
# Blender 3.x takes the legacy zip instead (scripts/build_addon.sh).
#
#   bash scripts/build_extension.sh [OUTPUT_DIR]    (default: dist/)
#   WELKIN_WHEEL=path.whl to bundle a given wheel (default: built into dist/ if missing)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

out_dir=${1:-dist}
version=$(sed -n 's/^project(welkin VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
manifest_version=$(sed -n 's/^version = "\(.*\)"/\1/p' addon/welkin/blender_manifest.toml)
if [[ "$version" != "$manifest_version" ]]; then
  echo "build_extension: version mismatch: CMakeLists.txt $version," \
       "blender_manifest.toml $manifest_version" >&2
  exit 1
fi

wheel=${WELKIN_WHEEL:-}
if [[ -z $wheel ]]; then
  wheel=$(ls -t dist/welkin-"$version"-cp311-*manylinux*.whl 2>/dev/null | head -n 1 || true)
  if [[ -z $wheel ]]; then
    bash scripts/build_wheel.sh dist
    wheel=$(ls -t dist/welkin-"$version"-cp311-*manylinux*.whl | head -n 1)
  fi
fi

bash scripts/install_blender_venvs.sh 4.5 >/dev/null
venv=build/venv-bpy-4.5
ext_cli=$(ls "$venv"/lib/python3.11/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py)

stage=build/extension/welkin
rm -rf "$stage"
mkdir -p "$stage/wheels"
cp -r addon/welkin/. "$stage/"
rm -rf "$stage/_native"
find "$stage" -name __pycache__ -prune -exec rm -rf {} +
cp "$wheel" "$stage/wheels/"
# The manifest names the wheel that was built (its manylinux tag is this machine's).
sed -i "s|^wheels = .*|wheels = [\"./wheels/$(basename "$wheel")\"]|" "$stage/blender_manifest.toml"

"$venv/bin/python" "$ext_cli" validate "$stage"
mkdir -p "$out_dir"
rm -f "$out_dir/welkin-$version-linux_x64.zip"
"$venv/bin/python" "$ext_cli" build --source-dir "$stage" --output-dir "$out_dir" --split-platforms
zip_path="$out_dir/welkin-$version-linux_x64.zip"
[[ -f $zip_path ]] || { echo "build_extension: $zip_path was not written" >&2; exit 1; }
"$venv/bin/python" "$ext_cli" validate "$zip_path"
echo "build_extension: wrote $(realpath "$zip_path") ($(du -h "$zip_path" | cut -f1))"
