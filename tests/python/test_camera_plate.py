# SPDX-License-Identifier: Apache-2.0
"""welkin.camera_plate (camera_plate.hpp) and `welkin plate`: the scene camera's plate.

Checks: on an equirectangular panorama the sky pixels equal welkin.sky_image's (the same
sky method on the same pixel-centre directions, 1e-4 relative) and the disc carries the
HDRI's sun energy (sum of the disc's radiance x pixel solid angle, 2 %: the HDRI
normalises it exactly, the plate samples it); Combined = Sky + AerialInscatter; sky
pixels have T = 1 and no in-scattering, ground pixels no sky; the CLI writes the same
numbers; bad input (no camera, a camera below the ground) is a ValueError naming the
field; a progress callback returning False cancels.

Run with PYTHONPATH=build /usr/bin/python3 -m pytest tests/python/test_camera_plate.py.
"""

import json
import math
import pathlib
import subprocess

import numpy as np
import pytest

import welkin

CLI = pathlib.Path(__file__).resolve().parents[2] / "build" / "welkin"
SUN = (6.0, 5.0)  # elevation, azimuth (degrees)
# A camera looking along +X with +Z up (local -Z -> +X, local +Y -> +Z, local +X -> -Y).
LOOK_X = [[0, 0, -1, 0], [-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]]


def scene(camera, resolution=(128, 64), z=2.0, method="lut"):
    m = [row[:] for row in LOOK_X]
    m[2][3] = z
    return json.dumps(
        {
            "version": 1,
            "method": method,
            "sun": {"elevation_deg": SUN[0], "azimuth_deg": SUN[1]},
            "camera": {"matrix_world": m, **camera},
            "resolution": {"x": resolution[0], "y": resolution[1], "percentage": 100},
        }
    )


def sun_vector():
    e, a = map(math.radians, SUN)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))


def solid_angles(width, height):
    lat = math.pi / 2 - math.pi * (np.arange(height) + 0.5) / height
    dlat = math.pi / height
    return (2 * math.pi / width) * 2 * np.cos(lat) * math.sin(dlat / 2)


def test_panorama_is_the_hdri():
    plate = welkin.camera_plate(scene({"type": "PANO"}))
    atm = welkin.Atmosphere.preset(welkin.Atmosphere.preset_names()[0])  # the scene's default
    hdri = welkin.sky_image(atm, 2.0, sun_vector(), 128, "lut", "rgb", sun_disc=True)
    sky_only = welkin.sky_image(atm, 2.0, sun_vector(), 128, "lut", "rgb", sun_disc=False)
    is_sky = np.isinf(plate["depth"])
    no_disc = np.abs(hdri - sky_only).max(axis=-1) == 0
    both = is_sky & no_disc
    err = np.abs(plate["sky"] - sky_only) / np.maximum(sky_only, 1e-6)
    assert err[both].max() < 1e-4
    omega = solid_angles(128, 64)[:, None]
    disc_plate = ((plate["sky"] - sky_only)[..., 1] * omega)[is_sky].sum()
    disc_hdri = ((hdri - sky_only)[..., 1] * omega).sum()
    assert disc_hdri > 0
    assert abs(disc_plate / disc_hdri - 1) < 0.02, (disc_plate, disc_hdri)


@pytest.mark.parametrize(
    "camera", [{"type": "PERSP"}, {"type": "ORTHO", "ortho_scale": 40}, {"type": "PANO"}]
)
def test_passes_compose(camera):
    # 50 m up, looking along +X 2 degrees down: local -Z = (cos, 0, -sin), +Y = (sin, 0, cos).
    m = json.loads(scene(camera))
    c, s = math.cos(math.radians(2)), math.sin(math.radians(2))
    m["camera"]["matrix_world"] = [[0, s, -c, 0], [-1, 0, 0, 0], [0, c, s, 50], [0, 0, 0, 1]]
    m["ground"] = {"enabled": False}  # the passes of a black ground (the lit one: tests/cpp/test_ground.cpp)
    plate = welkin.camera_plate(json.dumps(m))
    is_sky = np.isinf(plate["depth"])
    # Parallel orthographic rays 2 degrees down all reach the ground.
    assert (is_sky.mean() == 0) if camera["type"] == "ORTHO" else (0 < is_sky.mean() < 1)
    for k in ("combined", "sky", "inscatter", "transmittance"):
        assert np.isfinite(plate[k]).all()
    np.testing.assert_allclose(plate["combined"], plate["sky"] + plate["inscatter"], rtol=1e-6)
    assert (plate["transmittance"][is_sky] == 1).all() and (plate["inscatter"][is_sky] == 0).all()
    assert (plate["sky"][~is_sky] == 0).all()
    assert (plate["transmittance"][~is_sky] < 1).any() and (plate["inscatter"][~is_sky] > 0).all()


def test_cli_writes_the_same_plate(tmp_path):
    text = scene({"type": "PERSP"}, resolution=(48, 32))
    (tmp_path / "s.json").write_text(text)
    out = tmp_path / "plate.exr"
    subprocess.run(
        [str(CLI), "plate", "--scene", str(tmp_path / "s.json"), "-o", str(out)],
        check=True,
        capture_output=True,
    )
    pixels, names = welkin.read_exr(str(out))
    plate = welkin.camera_plate(text)
    got = np.stack([pixels[..., names.index(c)] for c in "RGB"], -1)
    np.testing.assert_array_equal(got, plate["combined"])
    for layer, key in (
        ("Welkin.Sky", "sky"),
        ("Welkin.AerialInscatter", "inscatter"),
        ("Welkin.AerialTransmittance", "transmittance"),
    ):
        got = np.stack([pixels[..., names.index(f"{layer}.{c}")] for c in "RGB"], -1)
        np.testing.assert_array_equal(got, plate[key])
    run = subprocess.run(
        [str(CLI), "plate", "--scene", str(tmp_path / "s.json"), "-o", str(out)],
        capture_output=True,
        text=True,
    )
    assert run.returncode != 0  # never replaces a file without --overwrite


def test_bad_input():
    with pytest.raises(ValueError, match="camera"):
        welkin.camera_plate(json.dumps({"version": 1}))
    with pytest.raises(ValueError, match="camera.matrix_world.*below the ground"):
        welkin.camera_plate(scene({"type": "PERSP"}, z=-20.0))


def test_cancel():
    with pytest.raises(KeyboardInterrupt):
        welkin.camera_plate(scene({"type": "PERSP"}), progress=lambda f: False)
