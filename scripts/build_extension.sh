#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the Blender Extension (Blender 4.2 and later): dist/welkin-<version>-linux_x64.zip,
# holding addon/welkin/ with its blender_manifest.toml and, in wheels/, the compiled core
# as the repaired wheels of scripts/build_wheel.sh, one per Python Blender runs: cp311
# (Blender 4.2-5.0) and cp313 (5.1 and later), both listed in the manifest. Blender installs
# the one of its own Python into the extensions' site-packages. Built with Blender's own
# extension tooling, blender_ext.py from the bpy 4.5 venv, and validated (the staged folder
# and the zip) by that of each Python line: 4.5's (3.11) and 5.3's (3.13)
# (scripts/install_blender_venvs.sh). Install it in Blender with Edit > Preferences > Get
# Extensions > Install from Disk, or headless with
# bpy.ops.extensions.package_install_files(filepath=..., repo="user_default").
# Blender 3.x takes the legacy zip instead (scripts/build_addon.sh).
#
#   bash scripts/build_extension.sh [OUTPUT_DIR]    (default: dist/)
#   WELKIN_WHEELS="a.whl b.whl" to bundle given wheels (default: the cp311 and cp313 ones
#   in dist/, built there by scripts/build_wheel.sh when missing)
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

read -r -a wheels <<<"${WELKIN_WHEELS:-}"
if ((${#wheels[@]} == 0)); then
  for tag in cp311 cp313; do
    wheel=$(ls -t dist/welkin-"$version"-"$tag"-*manylinux*.whl 2>/dev/null | head -n 1 || true)
    if [[ -z $wheel ]]; then
      WELKIN_WHEEL_PYTHONS=3.${tag#cp3} bash scripts/build_wheel.sh dist
      wheel=$(ls -t dist/welkin-"$version"-"$tag"-*manylinux*.whl | head -n 1)
    fi
    wheels+=("$wheel")
  done
fi
for tag in cp311 cp313; do
  printf '%s\n' "${wheels[@]##*/}" | grep -q "^welkin-$version-$tag-$tag-manylinux" || {
    echo "build_extension: no $tag wheel of welkin $version among: ${wheels[*]}" >&2; exit 1; }
done

# Blender's extension tooling of each Python line: 4.5's builds, both validate.
bash scripts/install_blender_venvs.sh 4.5 5.3 >/dev/null
ext_cli() {  # ext_cli VERSION ARGS...: blender_ext.py of that bpy venv
  local venv=build/venv-bpy-$1
  shift
  "$venv/bin/python" "$(ls "$venv"/lib/python3.*/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py)" "$@"
}

stage=build/extension/welkin
rm -rf "$stage"
mkdir -p "$stage/wheels"
cp -r addon/welkin/. "$stage/"
rm -rf "$stage/_native"
find "$stage" -name __pycache__ -prune -exec rm -rf {} +
cp "${wheels[@]}" "$stage/wheels/"
# The manifest names the wheels that were built (their manylinux tag is this machine's).
listed=$(printf '"./wheels/%s", ' "${wheels[@]##*/}")
sed -i "s|^wheels = .*|wheels = [${listed%, }]|" "$stage/blender_manifest.toml"
grep '^wheels = ' "$stage/blender_manifest.toml"

for v in 4.5 5.3; do ext_cli "$v" validate "$stage"; done
mkdir -p "$out_dir"
rm -f "$out_dir/welkin-$version-linux_x64.zip"
ext_cli 4.5 build --source-dir "$stage" --output-dir "$out_dir" --split-platforms
zip_path="$out_dir/welkin-$version-linux_x64.zip"
[[ -f $zip_path ]] || { echo "build_extension: $zip_path was not written" >&2; exit 1; }
for v in 4.5 5.3; do ext_cli "$v" validate "$zip_path"; done
echo "build_extension: wrote $(realpath "$zip_path") ($(du -h "$zip_path" | cut -f1))"
