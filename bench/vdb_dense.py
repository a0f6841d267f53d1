# SPDX-License-Identifier: Apache-2.0
"""Writes a dense density array as an OpenVDB file (a FloatGrid named "density") with
OpenVDB's own Python module, pyopenvdb (Debian's python3-openvdb).

Blender 3.4 run with --python-use-system-env imports pyopenvdb directly. The Pythons that
cannot (PyPI's bpy 4.5 / 5.0 in their venvs: OpenVDB publishes no Python wheel for them)
hand the array to Debian's /usr/bin/python3 in a subprocess, which runs this file as a
script; the file written is the same either way.

    write_density(path, density, ijk, voxel_m, tolerance=None, prune=False)
"""

import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

SYSTEM_PYTHON = os.environ.get("WELKIN_OPENVDB_PYTHON", "/usr/bin/python3")


def _write(vdb, path, density, ijk, voxel_m, tolerance, prune):
    grid = vdb.FloatGrid()
    grid.name = "density"
    grid.transform = vdb.createLinearTransform(voxelSize=float(voxel_m))
    if tolerance is None:
        grid.copyFromArray(density, ijk=tuple(int(i) for i in ijk))
    else:
        grid.copyFromArray(density, ijk=tuple(int(i) for i in ijk), tolerance=float(tolerance))
    if prune:
        grid.prune()
    vdb.write(str(path), grids=[grid])


def write_density(path, density, ijk, voxel_m, tolerance=None, prune=False):
    """Writes `density` (3D, float32, indexed [i, j, k]) with its first voxel at index
    `ijk`, voxels of `voxel_m` metres, to `path`."""
    density = np.ascontiguousarray(density, dtype=np.float32)
    try:
        import pyopenvdb as vdb
    except ImportError:
        vdb = None
    if vdb is not None:
        _write(vdb, path, density, ijk, voxel_m, tolerance, prune)
        return
    with tempfile.TemporaryDirectory(prefix="welkin_vdb_") as tmp:
        array = pathlib.Path(tmp) / "density.npy"
        np.save(array, density)
        args = [
            SYSTEM_PYTHON,
            str(pathlib.Path(__file__).resolve()),
            str(path),
            str(array),
            ",".join(str(int(i)) for i in ijk),
            repr(float(voxel_m)),
            "" if tolerance is None else repr(float(tolerance)),
            "1" if prune else "0",
        ]
        # The child's environment without this Python's venv and paths: Debian's python3
        # with its own numpy and pyopenvdb.
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
        result = subprocess.run(args, env=env, capture_output=True, text=True)
        if result.returncode != 0:
            raise RuntimeError(
                f"writing {path} with {SYSTEM_PYTHON} and pyopenvdb "
                f"(python3-openvdb) failed: {result.stderr.strip()}"
            )


def _main(argv):
    import pyopenvdb as vdb

    path, array, ijk, voxel_m, tolerance, prune = argv
    _write(
        vdb,
        path,
        np.load(array),
        [int(i) for i in ijk.split(",")],
        float(voxel_m),
        float(tolerance) if tolerance else None,
        prune == "1",
    )


if __name__ == "__main__":
    _main(sys.argv[1:])
