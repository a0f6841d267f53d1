# SPDX-License-Identifier: Apache-2.0
"""Cloud scenes for the headless Blender tests: a VDB sequence written with pyopenvdb
(python3-openvdb: in Blender 3.4's system Python, or Debian's python3 in a subprocess for
PyPI's bpy, bench/vdb_dense.py), a Volume object showing it, and a small procedural
layer."""

import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "bench"))
from vdb_dense import write_density  # noqa: E402


def write_vdb_sequence(directory, stem="cloud", frames=(1, 2, 3), size=16, voxel_m=50.0, value=None):
    """Writes <stem>.NNNN.vdb for each frame: a ball of density (FloatGrid "density") of
    `size` voxels of `voxel_m` metres, centred on the grid's origin, its value growing with
    the frame (frame f: f x value, default 1), so frames differ. Returns the paths."""
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    i = np.arange(size, dtype=np.float64) - (size - 1) / 2.0
    x, y, z = np.meshgrid(i, i, i, indexing="ij")
    ball = np.clip(1.0 - np.sqrt(x * x + y * y + z * z) / (size / 2.0), 0.0, 1.0)
    paths = []
    for f in frames:
        path = directory / f"{stem}.{f:04d}.vdb"
        write_density(path, (ball * f * (value or 1.0)).astype(np.float32), (-(size // 2),) * 3, voxel_m)
        paths.append(path)
    return paths


def add_volume(scene, first_file, name="Cloud", location=(0.0, 0.0, 2000.0), sequence=3):
    """A Volume object showing `first_file` (a sequence of `sequence` frames from frame 1
    when sequence > 0), marked as a Welkin cloud."""
    vol = bpy.data.volumes.new(name)
    vol.filepath = str(first_file)
    if sequence:
        vol.is_sequence = True
        vol.frame_start = 1
        vol.frame_duration = sequence
    ob = bpy.data.objects.new(name, vol)
    ob.location = location
    scene.collection.objects.link(ob)
    ob.welkin_cloud.enabled = True
    bpy.context.view_layer.update()
    return ob


def quick_cloudy_world(world):
    """The world's sky at the tests' quick settings: lut, 256 wide, a short cloud march
    (24 steps, 3 light steps, 1 ambient step, all scattering orders). Returns the world's
    cloud settings."""
    world.welkin.method = "lut"
    world.welkin.resolution = "256"
    c = world.welkin_clouds
    c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 24, 3, 1, 2
    return c


def add_layer(world, **values):
    layer = world.welkin_clouds.layers.add()
    layer.name = "Test Layer"
    for k, v in values.items():
        setattr(layer, k, v)
    return layer
