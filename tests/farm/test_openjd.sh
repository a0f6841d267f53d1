#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The Open Job Description template for Deadline Cloud (farm/openjd/welkin_render.yaml),
# run locally by PyPI's openjd-cli (build/venv-openjd, scripts/install_openjd.sh) with
# Debian's Blender 3.4 and the legacy add-on installed headless into a shared scripts
# folder (docs/pipelines.md#deadline-cloud-open-job-description):
#  1. `openjd check` validates the template;
#  2. `openjd run` of frames 1-3 of the aerial demo (the sun rising, Write Pass Files on)
#     with frame 2 forced to fail (a foreign file where its pass file goes): the run fails,
#     frame 2 has no file; with the cause removed, frame 2 alone completes the sequence,
#     and every frame equals the local `-a` bit for bit;
#  3. without the add-on in the worker's environment the task fails and writes nothing.
#
#   bash tests/farm/test_openjd.sh          (scripts/build.sh built build/ first)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."

openjd=${WELKIN_OPENJD:-build/venv-openjd/bin/openjd}
[[ -x $openjd ]] || { echo "test_openjd: FAILED: $openjd missing (bash scripts/install_openjd.sh)" >&2; exit 1; }
template=farm/openjd/welkin_render.yaml

scratch=$(mktemp -d "${TMPDIR:-/tmp}/welkin_test_openjd.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
trap 'exit 143' TERM INT
source tests/farm/farm_common.sh

"$openjd" check "$template"

install_addon
make_demo 3

run() {  # run LOG FRAMES: openjd run of the template's Render step
  local log=$1 frames=$2
  "$openjd" run "$template" --step Render -p "BlendFile=$blend" -p "OutputDir=$out" \
    -p "Frames=$frames" >"$log" 2>&1
}

out=$scratch/shared/out
mkdir -p "$out"
echo "not Welkin's" >"$out/f_welkin_aerial_0002.exr"
if run "$scratch/run1.log" 1-3; then
  tail -n 30 "$scratch/run1.log"
  fail "openjd run succeeded with frame 2 failing"
fi
grep -q "frame 2 failed" "$scratch/run1.log" || { tail -n 40 "$scratch/run1.log"; fail "the log does not say frame 2 failed"; }
[[ -f $out/f_0001.exr ]] || fail "frame 1 is missing"
[[ ! -e $out/f_0002.exr ]] || fail "frame 2 failed but its file is on disk"
echo "test_openjd: frame 2 failed its task, no file for it"

rm "$out/f_welkin_aerial_0002.exr"
run "$scratch/run2.log" 2-3 || { tail -n 40 "$scratch/run2.log"; fail "openjd run of frames 2-3"; }
compare "$out" 3

empty=$scratch/shared/no_addon
mkdir -p "$empty"
out=$scratch/shared/none
if BLENDER_USER_SCRIPTS=$empty run "$scratch/run3.log" 1; then
  fail "openjd run succeeded without the add-on"
fi
grep -q "Welkin add-on is not installed" "$scratch/run3.log" || { tail -n 30 "$scratch/run3.log"; fail "the log does not say the add-on is missing"; }
[[ -z $(ls -A "$out" 2>/dev/null) ]] || fail "a task without the add-on wrote $(ls "$out")"
echo "test_openjd: without the add-on: the task fails, nothing written"
echo "test_openjd: passed"
