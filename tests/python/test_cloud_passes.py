# SPDX-License-Identifier: Apache-2.0
"""Clouds in scenes: the scene JSON's "clouds" through the module, welkin.cloud_passes
(Welkin.Clouds / Welkin.CloudDepth for the scene camera), camera_plate's cloud passes,
and `welkin clouds` / `welkin aerial` / `welkin plate` / `welkin sky --scene` with clouds.

Checks: a constant VDB cube seen through its middle by an orthographic camera has the
closed-form opacity 1 - exp(-tau) and pixels beside it alpha 0 and depth 1e10; a depth in
front of the cube hides it; the plate's Combined is the clouds over the clear plate; the
CLI writes the module's numbers; a missing VDB fails naming clouds.volumes[0].file with
rc != 0 and no file; progress returning False cancels.

Run with PYTHONPATH=build /usr/bin/python3 -m pytest tests/python/test_cloud_passes.py.
"""

import json
import pathlib
import subprocess

import numpy as np
import pytest

import welkin

openvdb = pytest.importorskip("pyopenvdb")

CLI = pathlib.Path(__file__).resolve().parents[2] / "build" / "welkin"
# Looking along +X with +Z up (local -Z -> +X, local +Y -> +Z, local +X -> -Y), 50 m up.
LOOK_X = [[0, 0, -1, 0], [-1, 0, 0, 0], [0, 1, 0, 50], [0, 0, 0, 1]]
VOXEL, N, SCALE = 10.0, 10, 0.004  # a cube of 2N + 1 voxels of value 1, sigma_t = SCALE
CUBE_X = 1000.0  # the cube's centre, 1 km ahead


def write_cube(path):
    grid = openvdb.FloatGrid()
    grid.name = "density"
    grid.transform = openvdb.createLinearTransform(voxelSize=VOXEL)
    grid.copyFromArray(np.ones((2 * N + 1,) * 3, np.float32), ijk=(-N, -N, -N), tolerance=0)
    openvdb.write(str(path), grids=[grid])


def scene_json(vdb_file, camera=None, resolution=(8, 4), atmosphere="bruneton2017"):
    cam = camera or {"type": "ORTHO", "ortho_scale": 400.0}
    return json.dumps(
        {
            "version": 1,
            "method": "lut",
            "atmosphere": atmosphere,
            "sun": {"elevation_deg": 30, "azimuth_deg": 20},
            "camera": {"matrix_world": LOOK_X, **cam},
            "resolution": {"x": resolution[0], "y": resolution[1], "percentage": 100},
            "clouds": {
                "volumes": [
                    {
                        "name": "Cube",
                        "file": str(vdb_file),
                        "density_scale": SCALE,
                        "matrix_world": [[1, 0, 0, CUBE_X], [0, 1, 0, 0], [0, 0, 1, 50], [0, 0, 0, 1]],
                    }
                ],
                "lighting": {"max_steps": 128, "min_transmittance": 0.0},
            },
        }
    )


def test_scene_json_clouds(tmp_path):
    s = welkin.SceneDescription.from_json_string(json.dumps({"version": 1}))
    assert not s.has_clouds
    text = json.dumps(
        {"version": 1, "clouds": {"layers": [{"coverage": 0.3}], "volumes": [{"file": "cache/c.vdb"}]}}
    )
    s = welkin.SceneDescription.from_json_string(text, base_directory=str(tmp_path))
    assert s.has_clouds
    written = json.loads(s.to_json_string())["clouds"]
    assert written["volumes"][0]["file"] == str(tmp_path / "cache" / "c.vdb")
    assert written["layers"][0]["coverage"] == 0.3
    assert written["lighting"]["max_steps"] == 96  # every default written
    (tmp_path / "s.json").write_text(text)
    s = welkin.SceneDescription.from_json(str(tmp_path / "s.json"))
    assert json.loads(s.to_json_string())["clouds"]["volumes"][0]["file"] == str(tmp_path / "cache" / "c.vdb")
    with pytest.raises(ValueError, match=r"clouds\.layers\[0\]\.coverage: must be in \[0, 1\]"):
        welkin.SceneDescription.from_json_string(
            json.dumps({"version": 1, "clouds": {"layers": [{"coverage": 2}]}})
        )
    with pytest.raises(ValueError, match=r"clouds\.volumes\[0\]\.grd"):
        welkin.SceneDescription.from_json_string(
            json.dumps({"version": 1, "clouds": {"volumes": [{"file": "a.vdb", "grd": "density"}]}})
        )


def test_constant_cube_closed_form(tmp_path):
    write_cube(tmp_path / "cube.vdb")
    passes = welkin.cloud_passes(scene_json(tmp_path / "cube.vdb"))
    clouds, depth = passes["Welkin.Clouds"], passes["Welkin.CloudDepth"]
    assert clouds.shape == (4, 8, 4) and clouds.dtype == np.float32
    assert depth.shape == (4, 8) and depth.dtype == np.float32
    # Orthographic rays 50 m apart over 400 m: columns 2..5 (|y| <= 75 m) and every row
    # (|z - 50| <= 75 m) cross the cube (|x - CUBE_X|, |y|, |z - 50| <= N VOXEL = 100 m)
    # where the grid is 1: over 2N voxels between the outer voxel centres, plus the
    # trilinear ramps to the inactive neighbours, half a voxel of density on each side:
    # tau = SCALE VOXEL (2N + 1).
    tau = SCALE * VOXEL * (2 * N + 1)
    inside = clouds[:, 2:6, 3]
    np.testing.assert_allclose(inside, 1 - np.exp(-tau), rtol=1e-3)
    assert (clouds[..., :3][:, 2:6] > 0).all()
    # The depth lies within the cube (along the view axis: x from the camera at x = 0).
    assert ((depth[:, 2:6] > CUBE_X - N * VOXEL) & (depth[:, 2:6] < CUBE_X)).all()
    # Columns 0, 1, 6, 7 (|y| >= 125 m, beyond the support's 110 m) see no cloud.
    for col in (0, 1, 6, 7):
        assert (clouds[:, col] == 0).all()
        assert (depth[:, col] == np.float32(1e10)).all()

    # Geometry in front hides the cloud; geometry behind it changes nothing.
    z = np.full((4, 8), 1e10, np.float32)
    z[:, 3] = 500.0
    z[:, 4] = 5000.0
    hidden = welkin.cloud_passes(scene_json(tmp_path / "cube.vdb"), z)
    assert (hidden["Welkin.Clouds"][:, 3] == 0).all()
    assert (hidden["Welkin.CloudDepth"][:, 3] == np.float32(1e10)).all()
    np.testing.assert_array_equal(hidden["Welkin.Clouds"][:, 4], clouds[:, 4])
    with pytest.raises(ValueError, match="depth"):
        welkin.cloud_passes(scene_json(tmp_path / "cube.vdb"), np.zeros((3, 8), np.float32))
    with pytest.raises(KeyboardInterrupt):
        welkin.cloud_passes(scene_json(tmp_path / "cube.vdb"), progress=lambda f: False)


def test_plate_composites_the_clouds(tmp_path):
    write_cube(tmp_path / "cube.vdb")
    text = scene_json(tmp_path / "cube.vdb", camera={"type": "PERSP", "lens_mm": 50}, resolution=(32, 16))
    m = json.loads(text)
    m["ground"] = {"enabled": False}  # clouds over the black ground: Combined's identity below
    text = json.dumps(m)
    plate = welkin.camera_plate(text)
    clear = json.loads(text)
    del clear["clouds"]
    clear_plate = welkin.camera_plate(json.dumps(clear))
    assert plate["clouds"].shape == (16, 32, 4) and plate["cloud_depth"].shape == (16, 32)
    assert (clear_plate["clouds"] == 0).all() and (clear_plate["cloud_depth"] == np.float32(1e10)).all()
    a = plate["clouds"][..., 3:]
    assert (a > 0.1).sum() > 10
    expected = plate["clouds"][..., :3] + (1 - a) * (clear_plate["sky"] + clear_plate["inscatter"])
    np.testing.assert_allclose(plate["combined"], expected, rtol=1e-6, atol=1e-7)
    # The plate's passes are the cloud passes on the plate's ground depth.
    passes = welkin.cloud_passes(text, clear_plate["depth"])
    np.testing.assert_array_equal(plate["clouds"], passes["Welkin.Clouds"])
    np.testing.assert_array_equal(plate["cloud_depth"], passes["Welkin.CloudDepth"])


def test_cli_cloud_passes(tmp_path):
    write_cube(tmp_path / "cube.vdb")
    text = scene_json("cube.vdb")  # relative: resolved against the JSON file's folder
    (tmp_path / "s.json").write_text(text)
    passes = welkin.cloud_passes(scene_json(tmp_path / "cube.vdb"))
    out = tmp_path / "clouds.exr"
    subprocess.run(
        [str(CLI), "clouds", "--scene", str(tmp_path / "s.json"), "-o", str(out)],
        check=True,
        capture_output=True,
    )
    pixels, names = welkin.read_exr(str(out))
    got = np.stack([pixels[..., names.index(f"Welkin.Clouds.{c}")] for c in "RGBA"], -1)
    np.testing.assert_array_equal(got, passes["Welkin.Clouds"])
    np.testing.assert_array_equal(
        pixels[..., names.index("Welkin.CloudDepth.Z")], passes["Welkin.CloudDepth"]
    )

    # aerial with a depth: the aerial layers plus the cloud layers, the clouds ending at it.
    depth = np.full((4, 8), 1e10, np.float32)
    depth[:, 3] = 500.0
    welkin.write_exr(str(tmp_path / "depth.exr"), depth[..., None], ["Z"])
    out = tmp_path / "aerial.exr"
    subprocess.run(
        [
            str(CLI),
            "aerial",
            "--scene",
            str(tmp_path / "s.json"),
            "--depth",
            str(tmp_path / "depth.exr"),
            "-o",
            str(out),
        ],
        check=True,
        capture_output=True,
    )
    pixels, names = welkin.read_exr(str(out))
    hidden = welkin.cloud_passes(scene_json(tmp_path / "cube.vdb"), depth)
    got = np.stack([pixels[..., names.index(f"Welkin.Clouds.{c}")] for c in "RGBA"], -1)
    np.testing.assert_array_equal(got, hidden["Welkin.Clouds"])
    assert "Welkin.AerialInscatter.R" in names

    # plate: the cloud layers always (alpha 0 without clouds).
    out = tmp_path / "plate.exr"
    subprocess.run(
        [str(CLI), "plate", "--scene", str(tmp_path / "s.json"), "-o", str(out)],
        check=True,
        capture_output=True,
    )
    pixels, names = welkin.read_exr(str(out))
    got = np.stack([pixels[..., names.index(f"Welkin.Clouds.{c}")] for c in "RGBA"], -1)
    np.testing.assert_array_equal(got, welkin.camera_plate(scene_json(tmp_path / "cube.vdb"))["clouds"])


def test_cli_missing_vdb_names_the_key(tmp_path):
    (tmp_path / "s.json").write_text(scene_json("missing.vdb"))
    for command in (["clouds"], ["plate"], ["sky", "--width", "16"]):
        out = tmp_path / "out.exr"
        run = subprocess.run(
            [str(CLI), *command, "--scene", str(tmp_path / "s.json"), "-o", str(out)],
            capture_output=True,
            text=True,
        )
        assert run.returncode != 0, command
        assert "clouds.volumes[0].file" in run.stderr and "missing.vdb" in run.stderr, run.stderr
        assert not out.exists()
    with pytest.raises(ValueError, match=r"clouds\.volumes\[0\]\.file.*missing\.vdb"):
        welkin.cloud_passes(welkin.SceneDescription.from_json(str(tmp_path / "s.json")))


def test_cli_sky_scene_has_its_clouds(tmp_path):
    # A cloud deck over the whole sky: the scene's sky with clouds differs from the clear one
    # above the horizon, and is the same as the clear one below it (no cloud there).
    base = {"version": 1, "method": "lut", "sun": {"elevation_deg": 30, "azimuth_deg": 0}}
    cloudy = dict(
        base,
        clouds={
            "layers": [
                {"bottom_altitude_m": 1000, "top_altitude_m": 2000, "coverage": 1.0, "weather_variation": 0.0}
            ]
        },
    )
    for name, s in (("clear", base), ("cloudy", cloudy)):
        (tmp_path / f"{name}.json").write_text(json.dumps(s))
        subprocess.run(
            [
                str(CLI),
                "sky",
                "--scene",
                str(tmp_path / f"{name}.json"),
                "--width",
                "32",
                "--no-sun-disc",
                "-o",
                str(tmp_path / f"{name}.exr"),
            ],
            check=True,
            capture_output=True,
        )
    clear, _ = welkin.read_exr(str(tmp_path / "clear.exr"))
    cloud, _ = welkin.read_exr(str(tmp_path / "cloudy.exr"))
    assert np.abs(cloud[:6] - clear[:6]).max() > 0.05 * clear[:6].max()
    np.testing.assert_array_equal(cloud[10:], clear[10:])
