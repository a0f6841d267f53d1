#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the headless Blender tests (tests/blender/test_*.py) on every Blender Welkin
# supports, each with the add-on installed from its built package, as a user installs it:
#   3.4            Debian's `blender`, the legacy add-on zip (scripts/build_addon.sh: the
#                  module built by scripts/build.sh for /usr/bin/python3 in welkin/_native/);
#   4.2, 4.5, 5.0  PyPI's bpy (Python 3.11) and
#   5.1, 5.2, 5.3  PyPI's bpy (Python 3.13), in build/venv-bpy-<version>
#                  (scripts/install_blender_venvs.sh), through tests/blender/bpy_blender.py
#                  (Blender's command line over the bpy module); each installs the one
#                  Extension (scripts/build_extension.sh) from its zip, which carries the
#                  compiled core as repaired wheels for cp311 and cp313
#                  (scripts/build_wheel.sh), and Blender takes the wheel of its Python.
# The packages are built once, into build/blender_dist/; each wheel is checked outside
# Blender too, in a venv of its own Python (scripts/check_wheel.sh). Every test runs on
# every version even when one fails; a test that cannot run on a version prints
# "SKIPPED ... : reason". Prints each suite's time; the exit status is non-zero if any test
# failed. A test that runs longer than $WELKIN_TEST_TIMEOUT seconds (900) is stopped and
# fails.
#
#   bash scripts/test_blender.sh [-v 3.4,4.2,4.5,5.0,5.1,5.2,5.3] [tests/blender/test_<name>.py ...]
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

all_versions=3.4,4.2,4.5,5.0,5.1,5.2,5.3
versions=$all_versions
if [[ ${1:-} == -v ]]; then
  versions=$2
  shift 2
fi
IFS=, read -r -a versions <<<"$versions"
tests=("$@")
((${#tests[@]})) || tests=(tests/blender/test_*.py)

# Tests that fail on a version for a reason not yet found: each still runs and prints
# KNOWN FAILURE with the reason; it does not fail the run, and its passing does (so that
# the entry goes). Every entry is open work, named in the closing note of the change that
# added it.
declare -A known=(
  ["test_cycles_cloud_types@5.0"]="the fast march against Cycles on the types' VDB patches, Cycles' world the sky at the patch's altitude, every pixel its centre's ray: stratus 16 % bright on the shadow half (tolerance 15 %; the reference path tracer 4 %: the slab model's light on the deck's far side); every other mean, half and silver lining passes (docs/validation.md, Each cloud type against Cycles)"
)

# Every temporary file of the run (the tests', bpy_blender.py's user folders, Blender's
# session folders) goes into one folder, removed when the run ends however it ends: a test
# stopped by the timeout, or Blender exiting without its clean-up, leaves nothing in /tmp.
scratch=$(mktemp -d "${TMPDIR:-/tmp}/welkin_test_blender.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
export TMPDIR=$scratch

dist=build/blender_dist
mkdir -p "$dist"
version=$(sed -n 's/^project(welkin VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
failed=()
declare -A seconds

need_extension=0
for v in "${versions[@]}"; do
  case $v in
    3.4) ;;
    4.2 | 4.5 | 5.0 | 5.1 | 5.2 | 5.3) need_extension=1 ;;
    *) echo "test_blender: unknown Blender version $v ($all_versions)" >&2; exit 2 ;;
  esac
done

echo "--- packages (into $dist)"
if [[ " ${versions[*]} " == *" 3.4 "* ]]; then
  rm -f "$dist/welkin-$version.zip"
  if bash scripts/build_addon.sh "$dist"; then
    export WELKIN_ADDON_ZIP=$dist/welkin-$version.zip
  else
    failed+=(build_addon)
  fi
fi
if ((need_extension)); then
  rm -f "$dist"/welkin-*.whl "$dist"/welkin-*-linux_x64.zip
  # The wheels for Blender's Pythons, 3.11 and 3.13 (scripts/find_python.sh finds them).
  if bash scripts/build_wheel.sh "$dist" &&
     WELKIN_WHEELS="$(echo "$dist"/welkin-*manylinux*.whl)" bash scripts/build_extension.sh "$dist"; then
    export WELKIN_EXTENSION_ZIP=$dist/welkin-$version-linux_x64.zip
    echo "--- the wheels outside Blender (scripts/check_wheel.sh)"
    bash scripts/check_wheel.sh "$dist"/welkin-*manylinux*.whl || failed+=(check_wheel)
  else
    failed+=(build_extension)
  fi
fi
ls -l "$dist"

for v in "${versions[@]}"; do
  echo "=== Blender $v"
  start=$SECONDS
  for t in "${tests[@]}"; do
    echo "--- $t (Blender $v)"
    if [[ $v == 3.4 ]]; then
      [[ -n ${WELKIN_ADDON_ZIP:-} ]] || { failed+=("$t@$v"); continue; }
      run=(env PYTHONPATH="$(pwd)/build${PYTHONPATH:+:$PYTHONPATH}" blender)
    else
      [[ -n ${WELKIN_EXTENSION_ZIP:-} ]] || { failed+=("$t@$v"); continue; }
      # No PYTHONPATH: the compiled core comes from the Extension's wheel alone.
      run=(env -u PYTHONPATH "build/venv-bpy-$v/bin/python" tests/blender/bpy_blender.py)
    fi
    reason=${known["$(basename "$t" .py)@$v"]:-}
    if timeout -k 10 "${WELKIN_TEST_TIMEOUT:-900}" "${run[@]}" \
      -b --factory-startup --python-use-system-env --python-exit-code 1 --python "$t"; then
      [[ -z $reason ]] || { echo "test_blender: $t now passes on $v: take it off the known list"; failed+=("$t@$v(known)"); }
    elif [[ -n $reason ]]; then
      echo "test_blender: KNOWN FAILURE on Blender $v: $t: $reason"
    else
      failed+=("$t@$v")
    fi
  done
  seconds[$v]=$((SECONDS - start))
done

for v in "${versions[@]}"; do
  echo "test_blender: Blender $v: ${seconds[$v]} s"
done
if ((${#failed[@]})); then
  echo "test_blender: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "test_blender: all passed"
