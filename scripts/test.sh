#!/usr/bin/env bash
# Installs, builds, and runs every test suite: GoogleTest (ctest), the Python module
# (pytest), the fuzz targets for a bounded time (scripts/fuzz.sh), and the headless
# Blender tests once tests/blender/ exists. Every suite runs
# even when an earlier one fails; the exit status is non-zero if any failed.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/install_deps.sh
bash scripts/build.sh

failed=()

echo "=== C++ tests (ctest)"
ctest --test-dir build --output-on-failure -j"$(nproc)" || failed+=(ctest)

echo "=== Python tests (pytest)"
# Every suite has tests, so any non-zero status (5 included: nothing collected) fails.
PYTHONPATH="$(pwd)/build${PYTHONPATH:+:$PYTHONPATH}" \
  /usr/bin/python3 -m pytest tests/python -p no:cacheprovider -ra || failed+=(pytest)

echo "=== Fuzz (libFuzzer: the JSON and VDB readers, ${FUZZ_SECONDS:-30} s each)"
# A crash, sanitizer report, uncaught exception or timeout fails the suite (scripts/fuzz.sh).
bash scripts/fuzz.sh fuzz_json fuzz_vdb || failed+=(fuzz)

if compgen -G "tests/blender/test_*.py" >/dev/null; then
  echo "=== Blender tests (headless)"
  # The add-on zip the tests install, built once (scripts/build_addon.sh).
  if bash scripts/build_addon.sh build/addon_dist; then
    WELKIN_ADDON_ZIP=$(ls build/addon_dist/welkin-*.zip)
    export WELKIN_ADDON_ZIP
  else
    failed+=(build_addon)
  fi
  for t in tests/blender/test_*.py; do
    echo "--- $t"
    PYTHONPATH="$(pwd)/build${PYTHONPATH:+:$PYTHONPATH}" \
      blender -b --factory-startup --python-use-system-env --python-exit-code 1 \
      --python "$t" || failed+=("$t")
  done
fi

if ((${#failed[@]})); then
  echo "test: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "test: all suites passed"
