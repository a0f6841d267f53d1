# SPDX-License-Identifier: Apache-2.0
"""Running the `welkin` CLI from the tests: where it is, and how a Ctrl-C is checked.

The CLI is build/welkin unless WELKIN_CLI names another (an installed one)."""

import os
import pathlib
import resource
import signal
import subprocess
import time

import pytest

CLI = os.environ.get("WELKIN_CLI", str(pathlib.Path(__file__).resolve().parents[2] / "build" / "welkin"))


def files(path):
    """Every entry of a directory, hidden ones (temporary files) included."""
    return sorted(p.name for p in pathlib.Path(path).iterdir())


def children_cpu_seconds():
    """CPU time (user + system) of the child processes waited for so far: a bound on work
    that does not move with the machine's load, as wall-clock time does."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def assert_ctrl_c_cancels(args, cwd, after_s=1.5):
    """Starts `welkin *args`, sends SIGINT after `after_s` seconds, and checks that it
    stops promptly (< 5 s) with exit code 130, says "cancelled", and leaves `cwd` as it
    found it: no output, no temporary file. Skips if the command finished first."""
    before = files(cwd)
    p = subprocess.Popen(
        [CLI, *map(str, args)], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    time.sleep(after_s)
    if p.poll() is not None:
        _, err = p.communicate()
        pytest.skip(f"finished (rc {p.returncode}) before it could be interrupted: {err}")
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 130, err
    assert "cancelled" in err
    assert time.monotonic() - t0 < 5.0
    assert files(cwd) == before
