#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Welkin on a real Slurm scheduler (farm/slurm/): a one-node cluster on localhost
# (tests/farm/slurm_cluster.sh: Debian's munge and slurm-wlm, started here and stopped at
# the end whatever happens), Debian's Blender 3.4 on the worker with the legacy add-on
# installed headless into a shared scripts folder (BLENDER_USER_SCRIPTS, passed on by
# sbatch). The other Blender versions run the same add-on code in scripts/test_blender.sh.
#
#  1. The aerial demo (blend/make_aerial_demo.py) as a 4-frame sequence, the sun rising a
#     degree a frame, Write Pass Files on, 32 x 18 pixels, 4 samples; a local `-a` with
#     `-o` elsewhere is the reference (and shows Write Pass Files following -o).
#  2. `sbatch --array=1-4 farm/slurm/render.sbatch demo.blend OUT/f_####`, with frame 3
#     forced to fail (a foreign file where its pass file goes) and an earlier run's stale
#     image at frame 3's path: tasks 1, 2, 4 COMPLETED and their frames equal the local
#     ones bit for bit (Cycles' seed and sample count fix the result); task 3 FAILED and
#     no image for frame 3 (the stale one removed).
#  3. The cause removed, only task 3 resubmitted: COMPLETED, the sequence complete and
#     equal to the local one.
#  4. The add-on missing on the worker: the task FAILED, nothing written.
#  5. farm/slurm/sky.sbatch: three sky HDRIs of a time-lapse, each equal to a local
#     `welkin sky` bit for bit; a bad line FAILED with no file.
#
#   bash tests/farm/test_slurm.sh          (root; scripts/build.sh built build/ first)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
root=$(pwd)

if [[ $(id -u) -ne 0 ]]; then
  echo "test_slurm: FAILED: runs as root (munged and slurmd start as root here)" >&2
  exit 1
fi
for tool in /usr/sbin/munged /usr/sbin/slurmctld /usr/sbin/slurmd sbatch blender; do
  command -v "$tool" >/dev/null || { echo "test_slurm: FAILED: $tool missing (bash scripts/install_deps.sh)" >&2; exit 1; }
done

scratch=$(mktemp -d "${TMPDIR:-/tmp}/welkin_test_slurm.XXXXXX")
source tests/farm/slurm_cluster.sh
cleanup() {
  local rc=$?
  cluster_stop
  if ((rc != 0)); then
    echo "--- logs (test_slurm failed)"
    tail -n 30 "$scratch"/cluster/slurmctld.log "$scratch"/cluster/slurmd.log 2>/dev/null || true
    tail -n 40 "$scratch"/work/*.log 2>/dev/null || true
  fi
  rm -rf "$scratch"
}
trap cleanup EXIT
trap 'exit 143' TERM INT  # a timeout's signal still stops the cluster
deadline=$((SECONDS + ${WELKIN_SLURM_TIMEOUT:-900}))

source tests/farm/farm_common.sh
install_addon
make_demo 4

# --- the cluster
cluster_start "$scratch/cluster"
work=$scratch/work
mkdir -p "$work"
cd "$work"

wait_job() {  # wait_job JOB: until none of its tasks is pending or running
  while squeue -h -j "$1" 2>/dev/null | grep -q .; do
    ((SECONDS < deadline)) || fail "job $1 still running at the time limit"
    sleep 1
  done
}
task_state() {  # task_state JOB TASK
  scontrol -o show job "$1" | awk -v t="ArrayTaskId=$2" '$0 ~ t" " {for (i = 1; i <= NF; i++) if ($i ~ /^JobState=/) print substr($i, 10)}'
}

out=$scratch/shared/out
mkdir -p "$out"
# Frame 3 fails: a file that is not Welkin's where its pass file goes (never replaced).
echo "not Welkin's" >"$out/f_welkin_aerial_0003.exr"
# An earlier run's image at frame 3's path: the failed task must not leave it.
cp "$local_out/f_0001.exr" "$out/f_0003.exr"
touch -d '1 hour ago' "$out/f_0003.exr"
job=$(sbatch --parsable --array=1-4 "$root/farm/slurm/render.sbatch" "$blend" "$out/f_####")
echo "test_slurm: submitted job $job (frames 1-4)"
wait_job "$job"
for t in 1 2 4; do
  state=$(task_state "$job" $t)
  [[ $state == COMPLETED ]] || fail "task $t is $state, expected COMPLETED"
done
state=$(task_state "$job" 3)
[[ $state == FAILED ]] || fail "task 3 is $state, expected FAILED"
[[ ! -e $out/f_0003.exr ]] || fail "frame 3 failed but $out/f_0003.exr is on disk"
grep -q "frame 3 failed" welkin-render-"${job}"_3.log || fail "task 3's log does not say why it failed"
[[ $(cat "$out/f_welkin_aerial_0003.exr") == "not Welkin's" ]] || fail "the foreign file was replaced"
echo "test_slurm: tasks 1, 2, 4 COMPLETED; task 3 FAILED with no file for frame 3"

# Only the failed task again, its cause removed.
rm "$out/f_welkin_aerial_0003.exr"
job2=$(sbatch --parsable --array=3 "$root/farm/slurm/render.sbatch" "$blend" "$out/f_####")
wait_job "$job2"
state=$(task_state "$job2" 3)
[[ $state == COMPLETED ]] || fail "the resubmitted task 3 is $state"
compare "$out" 4

# The add-on missing where the environment points: FAILED, nothing rendered.
empty=$scratch/shared/no_addon
mkdir -p "$empty"
job3=$(BLENDER_USER_SCRIPTS=$empty sbatch --parsable --array=1 "$root/farm/slurm/render.sbatch" \
       "$blend" "$scratch/shared/none/f_####")
wait_job "$job3"
state=$(task_state "$job3" 1)
[[ $state == FAILED ]] || fail "a task without the add-on is $state, expected FAILED"
grep -q "Welkin add-on is not installed" welkin-render-"${job3}"_1.log || fail "the log does not say the add-on is missing"
[[ ! -e $scratch/shared/none ]] || fail "a task without the add-on wrote $(ls "$scratch/shared/none")"
echo "test_slurm: without the add-on: FAILED, nothing written"

# --- sky HDRIs without Blender: a short time-lapse
lines=$scratch/shared/day.txt
for elevation in 2 10 25; do
  echo "--preset hazy --method lut --sun-elevation $elevation --sun-azimuth 100 --width 64"
done >"$lines"
echo "--preset hazy --sun-elevation 95 --width 64" >>"$lines"  # out of range: fails
job4=$(WELKIN_CLI=$root/build/welkin sbatch --parsable --array=1-4 "$root/farm/slurm/sky.sbatch" \
       "$lines" "$scratch/shared/day/sky_####.exr")
wait_job "$job4"
for t in 1 2 3; do
  state=$(task_state "$job4" $t)
  [[ $state == COMPLETED ]] || fail "sky task $t is $state"
  read -r -a options < <(sed -n "${t}p" "$lines")
  "$root/build/welkin" sky "${options[@]}" -o "$scratch/local_sky_$t.exr" >/dev/null
  cmp -s "$scratch/local_sky_$t.exr" "$scratch/shared/day/sky_000$t.exr" ||
    fail "sky $t differs from the local welkin sky"
done
state=$(task_state "$job4" 4)
[[ $state == FAILED ]] || fail "the sky task with a bad line is $state, expected FAILED"
[[ ! -e $scratch/shared/day/sky_0004.exr ]] || fail "the failed sky task left a file"
echo "test_slurm: sky time-lapse: 3 HDRIs equal to local runs byte for byte; the bad line FAILED, no file"
echo "test_slurm: passed"
