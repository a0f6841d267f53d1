#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the installable Blender add-on: dist/welkin-<version>.zip, holding addon/welkin/
# and, in welkin/_native/, the compiled module built by scripts/build.sh for
# /usr/bin/python3 (Blender 3.4's Python 3.11). Install the zip in Blender with
# Edit > Preferences > Add-ons > Install, or headless with
# bpy.ops.preferences.addon_install(filepath=...) and addon_enable(module="welkin").
#
#   bash scripts/build_addon.sh [OUTPUT_DIR]    (default: dist/)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

out_dir=${1:-dist}
version=$(sed -n 's/^project(welkin VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
addon_version=$(/usr/bin/python3 -c '
import ast, sys
tree = ast.parse(open("addon/welkin/__init__.py").read())
for node in tree.body:
    if isinstance(node, ast.Assign) and node.targets[0].id == "bl_info":
        print(".".join(map(str, ast.literal_eval(node.value)["version"])))')
if [[ "$version" != "$addon_version" ]]; then
  echo "build_addon: version mismatch: CMakeLists.txt $version, bl_info $addon_version" >&2
  exit 1
fi

# The module, up to date (an incremental build when build/ exists).
if [[ -f build/CMakeCache.txt ]]; then
  cmake --build build -j"$(nproc)" --target welkin_py
else
  bash scripts/build.sh
fi
suffix=$(/usr/bin/python3 -c 'import importlib.machinery as m; print(m.EXTENSION_SUFFIXES[0])')
module="build/welkin${suffix}"
[[ -f "$module" ]] || { echo "build_addon: $module was not built" >&2; exit 1; }

mkdir -p "$out_dir"
zip_path="$out_dir/welkin-$version.zip"
/usr/bin/python3 - "$zip_path" "$module" <<'PY'
import os, pathlib, sys, zipfile
zip_path, module = sys.argv[1], pathlib.Path(sys.argv[2])
tmp = zip_path + ".tmp"
with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
    for path in sorted(pathlib.Path("addon/welkin").rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
            z.write(path, path.relative_to("addon"))
    z.write(module, f"welkin/_native/{module.name}")
os.replace(tmp, zip_path)
PY
echo "build_addon: wrote $(realpath "$zip_path")"
