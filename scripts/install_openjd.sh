#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs PyPI's openjd-cli (Open Job Description's reference runner: `openjd check`,
# `openjd run`) into build/venv-openjd, for tests/farm/test_openjd.sh, which runs the
# Deadline Cloud job template farm/openjd/welkin_render.yaml locally. Idempotent and quick
# when the pinned version is there. pip's own options apply (PIP_FIND_LINKS=...).
#
#   bash scripts/install_openjd.sh
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

pin=0.8.0
venv=build/venv-openjd
have=$("$venv/bin/python" -c 'import importlib.metadata as m; print(m.version("openjd-cli"))' 2>/dev/null || true)
if [[ $have == "$pin" ]]; then
  echo "install_openjd: $venv has openjd-cli $pin"
  exit 0
fi
rm -rf "$venv"
mkdir -p build
python3 -m venv "$venv"
"$venv/bin/pip" install -q "openjd-cli==$pin"
echo "install_openjd: $venv: openjd-cli $("$venv/bin/openjd" --version 2>/dev/null || echo "$pin")"
