# SPDX-License-Identifier: Apache-2.0
"""The viewport preview end to end, in a real window: runs viewport_window_script.py in a
windowed Blender under Xvfb (Mesa llvmpipe: the GL context any viewport has, no GPU
compute), which switches the 3D viewport to Rendered shading with the Welkin engine,
forces redraws and checks what view_draw drew against the core (its docstring lists the
checks). Its failures fail this test; its measurements (draw latency, the levels' times)
are printed.

Needs xvfb-run (Debian's xvfb, installed by scripts/install_deps.sh). Skipped, with a
message, only when no X server can be started here and $CI is not set; under CI a
missing X server fails.
"""

import json
import os
import pathlib
import shutil
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402

SCRIPT = pathlib.Path(__file__).resolve().parent / "viewport_window_script.py"


def no_x_server(reason):
    if os.environ.get("CI"):
        raise AssertionError(f"test_viewport_window: {reason} (CI must run this test)")
    print(f"test_viewport_window: SKIPPED: {reason}")
    sys.exit(0)


if t.is_module_bpy():
    t.skip(
        "test_viewport_window",
        "a windowed viewport needs a Blender binary with its window "
        "and GL context; PyPI's bpy is Blender as a Python module, without either (the "
        "preview's camera is tested headless by test_viewport_camera)",
    )

if shutil.which("xvfb-run") is None:
    no_x_server("xvfb-run not found: install Debian's xvfb (scripts/install_deps.sh does)")

result = t.TMP / "viewport_result.json"
env = dict(os.environ, WELKIN_ADDON_ZIP=str(t.addon_zip()), WELKIN_VIEWPORT_RESULT=str(result))
cmd = [
    "xvfb-run",
    "-a",
    "-s",
    "-screen 0 1280x800x24",
    "blender",
    "--factory-startup",
    "--python-use-system-env",
    "--python",
    str(SCRIPT),
]
proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
if not result.exists():
    tail = "\n".join(proc.stdout.splitlines()[-30:])
    if (
        "xvfb-run: error" in proc.stdout
        or "Xvfb failed" in proc.stdout
        or "cannot open display" in proc.stdout.lower()
    ):
        no_x_server(f"Xvfb could not start:\n{tail}")
    raise AssertionError(f"the windowed Blender wrote no result (rc {proc.returncode}):\n{tail}")
report = json.loads(result.read_text())
for key, value in report["notes"].items():
    print(f"  {key}: {value}")
t.check(not report["failures"], "viewport preview: " + "\n".join(report["failures"]))
t.done("test_viewport_window")
