#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Configures and builds everything (core, Python module, CLI, tests) in build/, Release,
# with the Python module built for /usr/bin/python3 (Blender's Python). WELKIN_WERROR=ON
# (what scripts/test.sh sets, so CI) turns compiler warnings into errors.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3 \
  -DWELKIN_WERROR="${WELKIN_WERROR:-OFF}"
cmake --build build -j"$(nproc)"
