# SPDX-License-Identifier: Apache-2.0
"""scripts/find_python.sh, which finds the interpreter of each Python line Blender runs
(3.11 for Blender 3.4-5.0, 3.13 for 5.1 and later) for the wheels and the bpy venvs."""

import os
import pathlib
import subprocess
import sys

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "find_python.sh"


def run(*args, **env):
    return subprocess.run(
        ["bash", str(SCRIPT), *args], capture_output=True, text=True, env={**os.environ, **env}
    )


def test_finds_a_python_of_the_line_asked_for():
    # This Python's own line is there (pytest runs in /usr/bin/python3, 3.11).
    line = f"{sys.version_info.major}.{sys.version_info.minor}"
    found = run(line, "--headers")
    assert found.returncode == 0, found.stderr
    path = found.stdout.strip()
    version = subprocess.run(
        [path, "-c", "import sys; print(sys.version_info[:2])"], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert version == str(sys.version_info[:2]), (path, version)


def test_the_override_is_the_only_candidate_and_a_wrong_one_fails_clearly():
    line = f"{sys.version_info.major}.{sys.version_info.minor}"
    other = "3.13" if line != "3.13" else "3.11"
    var = "WELKIN_PYTHON_" + other.replace(".", "_")
    refused = run(other, **{var: sys.executable})
    assert refused.returncode != 0 and refused.stdout == ""
    assert f"no Python {other} found" in refused.stderr and var in refused.stderr, refused.stderr
    accepted = run(line, **{"WELKIN_PYTHON_" + line.replace(".", "_"): sys.executable})
    assert accepted.returncode == 0
    assert pathlib.Path(accepted.stdout.strip()) == pathlib.Path(sys.executable).resolve()
