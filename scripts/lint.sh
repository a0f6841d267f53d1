#!/usr/bin/env bash
# One way to format and lint: clang-format (.clang-format) on the C++ of src/, include/,
# tests/ and bench/; ruff's formatter and linter (ruff.toml) and mypy (mypy.ini) on the
# Python; and the house's own checks: every path, section and anchor a comment or doc
# names exists (scripts/check_refs.py), every source file names its licence
# (scripts/check_spdx.py), no function too long (scripts/check_length.py: lizard).
# Pinned versions, in a venv of their own (build/venv-lint). Exits non-zero on any finding.
#   bash scripts/lint.sh          check
#   bash scripts/lint.sh --fix    apply clang-format, ruff's formatting and safe fixes and
#                                 the SPDX lines, then check
#   bash scripts/lint.sh --python ruff and mypy only
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

venv=build/venv-lint
want="ruff==0.17.6 mypy==2.4.1 lizard==1.24.3"
if [[ ! -x $venv/bin/ruff || ! -x $venv/bin/mypy || "$(cat $venv/.pins 2>/dev/null)" != "$want" ]]; then
  rm -rf "$venv"
  /usr/bin/python3 -m venv "$venv"
  # shellcheck disable=SC2086
  "$venv/bin/pip" install -q --disable-pip-version-check $want
  echo "$want" > "$venv/.pins"
fi
command -v clang-format >/dev/null || { echo "lint: clang-format is missing (scripts/install_deps.sh installs it)" >&2; exit 1; }

mapfile -t cxx < <(git ls-files '*.cpp' '*.hpp')
if [[ ${1:-} == --fix ]]; then
  clang-format -i "${cxx[@]}"
  "$venv/bin/ruff" format .
  "$venv/bin/ruff" check --fix .
  "$venv/bin/python" scripts/check_spdx.py --fix || true
fi

failed=()
if [[ ${1:-} != --python ]]; then
  clang-format --dry-run -Werror "${cxx[@]}" || failed+=(clang-format)
fi
"$venv/bin/ruff" format --check . || failed+=(ruff-format)
"$venv/bin/ruff" check . || failed+=(ruff)
if [[ -f mypy.ini ]]; then
  "$venv/bin/mypy" --config-file mypy.ini || failed+=(mypy)
fi
if [[ ${1:-} != --python ]]; then
  "$venv/bin/python" scripts/check_refs.py || failed+=(references)
  "$venv/bin/python" scripts/check_spdx.py || failed+=(spdx)
  "$venv/bin/python" scripts/check_length.py || failed+=(function-length)
fi
if ((${#failed[@]})); then
  echo "lint: FAILED: ${failed[*]} (bash scripts/lint.sh --fix applies the formatting)" >&2
  exit 1
fi
if [[ ${1:-} == --python ]]; then
  echo "lint: clean (ruff, mypy)"
else
  echo "lint: clean (${#cxx[@]} C++ files, ruff, mypy)"
fi
