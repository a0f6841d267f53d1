#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Finds the interpreter of one Python line (3.11 for Blender 3.4-5.0, 3.13 for Blender
# 5.1 and later): sourced by build_wheel.sh, check_wheel.sh, install_blender_venvs.sh and
# test_blender.sh, or run as `bash scripts/find_python.sh 3.13 [--headers]`, which prints
# its path. Looked for, first that runs and is that version:
#   $WELKIN_PYTHON_3_13 (or _3_11): a path, when set it is the only candidate;
#   python3 and python3.13 on PATH (pyenv's shims included: a shim of a version pyenv has
#   not selected fails to run and is passed over);
#   pyenv's installs, ${PYENV_ROOT:-~/.pyenv}/versions/3.13.*, the newest first;
#   /usr/local/bin/python3.13, /usr/bin/python3.13.
# --headers: also needs Python.h (building the module); Debian 12 has no python3.13-dev,
# pyenv's builds carry their headers. None found: a message naming what was tried and how
# to get one, and a non-zero status.

welkin_find_python() {
  local want=$1 headers=${2:-} var candidates=() c root
  var="WELKIN_PYTHON_${want/./_}"
  if [[ -n ${!var:-} ]]; then
    candidates=("${!var}")
  else
    root=${PYENV_ROOT:-$HOME/.pyenv}
    candidates=(python3 "python$want")
    while IFS= read -r c; do
      candidates+=("$c")
    done < <(ls -d "$root"/versions/"$want".*/bin/python"$want" 2>/dev/null | sort -rV)
    candidates+=("/usr/local/bin/python$want" "/usr/bin/python$want")
  fi
  local check="import sys, sysconfig, os
ok = sys.version_info[:2] == tuple(map(int, '$want'.split('.')))
if ok and '$headers' == '--headers':
    ok = os.path.isfile(os.path.join(sysconfig.get_paths()['include'], 'Python.h'))
if ok:
    print(os.path.realpath(sys.executable))
sys.exit(0 if ok else 1)"
  for c in "${candidates[@]}"; do
    if command -v "$c" >/dev/null 2>&1 && "$c" -c "$check" 2>/dev/null; then
      return 0
    fi
  done
  {
    echo "find_python: no Python $want${headers:+ with its headers (Python.h)} found; tried:" \
         "${candidates[*]}"
    echo "  install one (e.g. \`pyenv install $want\`: Debian 12 packages only 3.11)," \
         "or set $var to its interpreter"
  } >&2
  return 1
}

if [[ ${BASH_SOURCE[0]} == "$0" ]]; then
  set -euo pipefail
  welkin_find_python "$@"
fi
