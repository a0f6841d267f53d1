#!/usr/bin/env bash
# Installs the Blenders the tests run against besides Debian's 3.4: PyPI's `bpy` (Blender
# as a Python module, cp311) in one virtual environment per version, made from the Python
# 3.11 on PATH ($WELKIN_VENV_PYTHON to choose another):
#   build/venv-bpy-4.5   bpy==4.5.15 (4.5 LTS)
#   build/venv-bpy-5.0   bpy==5.0.1
# Idempotent and quick when they are there: a venv is (re)made only when its bpy is not the
# pinned one. pip's own options apply (PIP_FIND_LINKS=/dir/of/wheels to reuse downloads).
#
#   bash scripts/install_blender_venvs.sh [4.5|5.0 ...]    (default: all)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# The pinned versions; test.sh and the runner read the same list.
declare -A pins=([4.5]=4.5.15 [5.0]=5.0.1)

if [[ ! -r /etc/debian_version ]] || [[ $(cut -d. -f1 /etc/debian_version) != 12 ]]; then
  echo "install_blender_venvs: this project builds and tests on Debian 12 only" \
       "(/etc/debian_version: $(cat /etc/debian_version 2>/dev/null || echo missing))" >&2
  exit 1
fi

python=${WELKIN_VENV_PYTHON:-python3}
if ! "$python" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
  echo "install_blender_venvs: PyPI's bpy 4.5/5.0 wheels are cp311; $python is" \
       "$("$python" --version 2>&1 || echo missing) (set WELKIN_VENV_PYTHON to a Python 3.11)" >&2
  exit 1
fi

versions=("$@")
((${#versions[@]})) || versions=(4.5 5.0)
for v in "${versions[@]}"; do
  pin=${pins[$v]:-}
  [[ -n $pin ]] || { echo "install_blender_venvs: no pinned bpy for $v" >&2; exit 1; }
  venv=build/venv-bpy-$v
  have=$("$venv/bin/python" -c 'import importlib.metadata as m; print(m.version("bpy"))' 2>/dev/null || true)
  if [[ $have == "$pin" ]]; then
    echo "install_blender_venvs: $venv has bpy $pin"
    continue
  fi
  echo "install_blender_venvs: making $venv with bpy==$pin"
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check "bpy==$pin"
done
