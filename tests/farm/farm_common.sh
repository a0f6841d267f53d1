# SPDX-License-Identifier: Apache-2.0
# Shared by the farm tests (tests/farm/test_*.sh); sourced from the repository root with
# $scratch set: the add-on installed headless into a shared scripts folder, the aerial
# demo as a short sequence, its local reference render, and the comparison of frames.

root=$(pwd)

fail() {
  echo "${0##*/}: FAILED: $*" >&2
  exit 1
}

# install_addon: the legacy add-on zip for Debian's Blender 3.4, installed headless as
# docs/pipelines.md#slurm says, into $scratch/shared (exported for the workers).
install_addon() {
  local zip=${WELKIN_ADDON_ZIP:-}
  if [[ -z $zip ]]; then
    bash scripts/build_addon.sh "$scratch/dist" >/dev/null
    zip=$(ls "$scratch"/dist/welkin-*.zip)
  fi
  export BLENDER_USER_SCRIPTS=$scratch/shared/blender_scripts
  export BLENDER_USER_CONFIG=$scratch/shared/blender_config
  blender -b --factory-startup --python-expr \
    "import bpy; bpy.ops.preferences.addon_install(filepath='$zip')" >/dev/null
  [[ -f $BLENDER_USER_SCRIPTS/addons/welkin/__init__.py ]] ||
    fail "the add-on is not in $BLENDER_USER_SCRIPTS"
}

# make_demo FRAMES: $scratch/shared/demo/welkin_aerial_demo.blend, the aerial demo as a
# FRAMES-frame sequence (the sun rising a degree a frame, Write Pass Files on), 32 x 18
# pixels, 4 Cycles samples; then its local `-a` into $scratch/local with -o.
make_demo() {
  local frames=$1 f
  demo=$scratch/shared/demo
  blender -b --factory-startup --python-use-system-env --python blend/make_aerial_demo.py -- \
    --out "$demo" --size 32 --samples 4 --frames "$frames" --no-render \
    >"$scratch/make_demo.log" 2>&1 ||
    { tail -n 30 "$scratch/make_demo.log"; fail "blend/make_aerial_demo.py"; }
  blend=$demo/welkin_aerial_demo.blend
  local_out=$scratch/local
  blender -b "$blend" --addons welkin -o "$local_out/f_####" -a >"$scratch/local.log" 2>&1 ||
    { tail -n 30 "$scratch/local.log"; fail "the local -a render exited non-zero"; }
  for ((f = 1; f <= frames; f++)); do
    [[ -f $local_out/f_000$f.exr ]] || fail "the local render left no frame $f"
    # Write Pass Files follows -o: the passes are beside the frames, not at the saved path.
    [[ -f $local_out/f_welkin_aerial_000$f.exr ]] ||
      fail "no pass file for frame $f beside the frames of -o"
  done
  echo "${0##*/}: local reference: $frames frames and their pass files under the path of -o"
}

# compare DIR FRAMES: frames 1..FRAMES of DIR equal the local ones pixel for pixel (and
# the first and last differ: the sun moved).
compare() {
  PYTHONPATH=$root/build /usr/bin/python3 - "$1" "$local_out" "$2" <<'PY'
import sys
import numpy as np
import welkin
farm, local, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
for f in range(1, frames + 1):
    a, na = welkin.read_exr(f"{farm}/f_{f:04d}.exr")
    b, nb = welkin.read_exr(f"{local}/f_{f:04d}.exr")
    if na != nb or a.shape != b.shape:
        sys.exit(f"frame {f}: channels {na} {a.shape} != {nb} {b.shape}")
    if not np.isfinite(a).all() or a.max() <= 0.0:
        sys.exit(f"frame {f}: not a rendered image (max {a.max()})")
    if not np.array_equal(a, b):
        sys.exit(f"frame {f}: differs from the local render: max |diff| {np.abs(a - b).max()}")
first, last = (np.asarray(welkin.read_exr(f"{local}/f_{f:04d}.exr")[0]) for f in (1, frames))
if np.array_equal(first, last):
    sys.exit(f"frames 1 and {frames} are equal: the sun did not move")
print(f"{farm}: frames 1-{frames} equal the local render bit for bit")
PY
}
