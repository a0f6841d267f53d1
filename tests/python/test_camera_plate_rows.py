# SPDX-License-Identifier: Apache-2.0
"""welkin.camera_plate(scene, rows=(begin, end)): a band of the frame (the render engine's
tiles) has exactly the whole frame's values in those rows, for both aerial methods and for
the automatic sky method (chosen for the whole frame, not the band); bad ranges are
refused naming "rows"."""

import json

import numpy as np
import pytest

import welkin


def scene(method, aerial):
    d = {
        "version": 1,
        "atmosphere": "hazy",
        "sun": {"elevation_deg": 6, "azimuth_deg": 5},
        "method": method,
        "camera": {
            "matrix_world": [[0, 0, -1, 0], [-1, 0, 0, 0], [0, 1, 0, 50], [0, 0, 0, 1]],
            "type": "PERSP",
            "lens_mm": 30,
        },
        "resolution": {"x": 96, "y": 70, "percentage": 100},
        "aerial": {"method": aerial},
    }
    return welkin.SceneDescription.from_json_string(json.dumps(d))


@pytest.mark.parametrize("method,aerial", [("auto", "froxel"), ("lut", "raymarch")])
def test_bands_equal_the_whole_frame(method, aerial):
    s = scene(method, aerial)
    full = welkin.camera_plate(s)
    bands = [welkin.camera_plate(s, rows=(r, min(r + 16, 70))) for r in range(0, 70, 16)]
    assert [b["depth"].shape for b in bands] == [(16, 96)] * 4 + [(6, 96)]
    assert np.isinf(full["depth"]).any() and np.isfinite(full["depth"]).any()  # sky and ground
    for key in ("combined", "sky", "inscatter", "transmittance", "depth"):
        joined = np.concatenate([b[key] for b in bands])
        np.testing.assert_array_equal(joined, full[key], err_msg=key)
    assert {b["method"] for b in bands} == {full["method"]}


@pytest.mark.parametrize("rows", [(10, 5), (-1, 4), (0, 71), (3, 3)])
def test_bad_rows(rows):
    with pytest.raises(ValueError, match="rows"):
        welkin.camera_plate(scene("lut", "froxel"), rows=rows)


def cloudy_scene():
    d = json.loads(scene("lut", "froxel").to_json_string())
    d["clouds"] = {"layers": [{"coverage": 0.6}]}
    # Looking a little up, so that the band crosses cloud, sky and ground.
    d["camera"]["matrix_world"] = [[0, 0.2, -1, 0], [-1, 0, 0, 0], [0, 1, 0.2, 50], [0, 0, 0, 1]]
    d["resolution"] = {"x": 40, "y": 30, "percentage": 100}
    return welkin.SceneDescription.from_json_string(json.dumps(d))


KEYS = ("combined", "sky", "inscatter", "transmittance", "depth", "clouds", "cloud_depth")


@pytest.mark.parametrize(
    "make",
    [lambda: scene("auto", "froxel"), lambda: scene("lut", "raymarch"), cloudy_scene],
    ids=["auto-froxel", "lut-raymarch", "clouds"],
)
def test_prepared_bands_tile_the_whole_frame_exactly(make):
    """CameraPlateRenderer: the frame-wide part once, bands of uneven sizes (1 row, 7, the
    rest) rendered in any order concatenate to exactly camera_plate's whole frame."""
    s = make()
    full = welkin.camera_plate(s)
    renderer = welkin.CameraPlateRenderer(s)
    h = renderer.height
    assert (renderer.width, h) == full["depth"].shape[::-1]
    assert renderer.method == full["method"] and renderer.has_clouds == ("clouds" in s.to_json_string())
    cuts = [(8, h), (0, 1), (1, 8)]
    bands = dict((c, renderer.render(rows=c)) for c in cuts)
    whole = renderer.render()
    for key in KEYS:
        joined = np.concatenate([bands[c][key] for c in sorted(cuts)])
        np.testing.assert_array_equal(joined, full[key], err_msg=key)
        np.testing.assert_array_equal(whole[key], full[key], err_msg=key)
    if renderer.has_clouds:
        assert (full["clouds"][..., 3] > 0.01).any()  # some cloud in the frame


def test_prepared_bad_rows_and_scene():
    renderer = welkin.CameraPlateRenderer(scene("lut", "froxel"))
    for rows in [(10, 5), (-1, 4), (0, 71), (3, 3)]:
        with pytest.raises(ValueError, match="rows"):
            renderer.render(rows=rows)
    d = json.loads(scene("lut", "froxel").to_json_string())
    d["camera"]["matrix_world"][2][3] = -10.0
    with pytest.raises(ValueError, match="camera.matrix_world"):
        welkin.CameraPlateRenderer(json.dumps(d))
    with pytest.raises(ValueError, match="scene"):
        welkin.CameraPlateRenderer(3)
