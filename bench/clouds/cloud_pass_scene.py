# SPDX-License-Identifier: Apache-2.0
"""Writes a VDB ball and a 1920x1080 scene JSON that sees it, for timing the camera cloud
passes (docs/pipelines.md "Clouds in a scene"):

    /usr/bin/python3 bench/clouds/cloud_pass_scene.py OUT_DIR [--distance 3000] [--height 500]
    build/welkin clouds --scene OUT_DIR/scene.json -o OUT_DIR/clouds.exr

The ball: 61^3 voxels of 10 m, density 1 - r^2 (r from the centre, 1 at the surface),
density_scale 0.02 m^-1; the camera 2 m up looking along +X (35 mm lens), the sun 20 degrees
up at azimuth 30 degrees; the ball's centre `distance` m ahead and `height` m up.
"""

import argparse
import json
import pathlib

import numpy as np
import pyopenvdb as vdb

parser = argparse.ArgumentParser()
parser.add_argument("out", type=pathlib.Path)
parser.add_argument("--distance", type=float, default=3000.0)
parser.add_argument("--height", type=float, default=500.0)
args = parser.parse_args()
args.out.mkdir(parents=True, exist_ok=True)

n = 30
i, j, k = np.meshgrid(*[np.arange(-n, n + 1)] * 3, indexing="ij")
r2 = (i * i + j * j + k * k) / n**2
grid = vdb.FloatGrid()
grid.name = "density"
grid.transform = vdb.createLinearTransform(voxelSize=10.0)
grid.copyFromArray(np.clip(1 - r2, 0, None).astype(np.float32), ijk=(-n, -n, -n), tolerance=0)
vdb.write(str(args.out / "ball.vdb"), grids=[grid])

scene = {
    "version": 1,
    "method": "lut",
    "sun": {"elevation_deg": 20, "azimuth_deg": 30},
    "camera": {
        "matrix_world": [[0, 0, -1, 0], [-1, 0, 0, 0], [0, 1, 0, 2], [0, 0, 0, 1]],
        "type": "PERSP",
        "lens_mm": 35,
    },
    "resolution": {"x": 1920, "y": 1080, "percentage": 100},
    "clouds": {
        "volumes": [
            {
                "name": "Ball",
                "file": "ball.vdb",
                "density_scale": 0.02,
                "matrix_world": [
                    [1, 0, 0, args.distance],
                    [0, 1, 0, 0],
                    [0, 0, 1, args.height],
                    [0, 0, 0, 1],
                ],
            }
        ]
    },
}
(args.out / "scene.json").write_text(json.dumps(scene, indent=1))
print(args.out / "scene.json")
