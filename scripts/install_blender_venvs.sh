#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs the Blenders the tests run against besides Debian's 3.4: PyPI's `bpy` (Blender
# as a Python module) in one virtual environment per version, made from the Python that
# version runs (scripts/find_python.sh finds it: python3 on PATH, pyenv's installs, ...;
# $WELKIN_PYTHON_3_11 / $WELKIN_PYTHON_3_13 to choose one):
#   build/venv-bpy-4.2   bpy==4.2.23 (4.2 LTS)   Python 3.11
#   build/venv-bpy-4.5   bpy==4.5.15 (4.5 LTS)   Python 3.11
#   build/venv-bpy-5.0   bpy==5.0.1              Python 3.11
#   build/venv-bpy-5.1   bpy==5.1.2              Python 3.13
#   build/venv-bpy-5.2   bpy==5.2.4  (5.2 LTS)   Python 3.13
#   build/venv-bpy-5.3   bpy==5.3.0              Python 3.13
# (the newest of each line PyPI serves). Idempotent and quick when they are there: a venv
# is (re)made only when its bpy is not the pinned one. pip's own options apply
# (PIP_FIND_LINKS=/dir/of/wheels to reuse downloads).
#
#   bash scripts/install_blender_venvs.sh [4.2|4.5|5.0|5.1|5.2|5.3 ...]    (default: all)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/find_python.sh

# The pinned versions and their Pythons; test_blender.sh reads the same list.
declare -A pins=([4.2]=4.2.23 [4.5]=4.5.15 [5.0]=5.0.1 [5.1]=5.1.2 [5.2]=5.2.4 [5.3]=5.3.0)
declare -A pythons=([4.2]=3.11 [4.5]=3.11 [5.0]=3.11 [5.1]=3.13 [5.2]=3.13 [5.3]=3.13)

if [[ ! -r /etc/debian_version ]] || [[ $(cut -d. -f1 /etc/debian_version) != 12 ]]; then
  echo "install_blender_venvs: this project builds and tests on Debian 12 only" \
       "(/etc/debian_version: $(cat /etc/debian_version 2>/dev/null || echo missing))" >&2
  exit 1
fi

versions=("$@")
((${#versions[@]})) || versions=(4.2 4.5 5.0 5.1 5.2 5.3)
for v in "${versions[@]}"; do
  pin=${pins[$v]:-}
  [[ -n $pin ]] || { echo "install_blender_venvs: no pinned bpy for $v (${!pins[*]})" >&2; exit 1; }
  venv=build/venv-bpy-$v
  have=$("$venv/bin/python" -c 'import importlib.metadata as m; print(m.version("bpy"))' 2>/dev/null || true)
  if [[ $have == "$pin" ]]; then
    echo "install_blender_venvs: $venv has bpy $pin"
    continue
  fi
  # PyPI's bpy wheels are for one Python each: cp311 up to 5.0, cp313 from 5.1.
  python=$(welkin_find_python "${pythons[$v]}") || {
    echo "install_blender_venvs: bpy $pin needs Python ${pythons[$v]}" >&2; exit 1; }
  echo "install_blender_venvs: making $venv with bpy==$pin ($python)"
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check "bpy==$pin"
done
