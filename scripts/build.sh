#!/usr/bin/env bash
# Configures and builds everything (core, Python module, CLI, tests) in build/, Release,
# with the Python module built for /usr/bin/python3 (Blender's Python).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3
cmake --build build -j"$(nproc)"
