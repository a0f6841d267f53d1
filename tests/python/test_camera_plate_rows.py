"""welkin.camera_plate(scene, rows=(begin, end)): a band of the frame (the render engine's
tiles) has exactly the whole frame's values in those rows, for both aerial methods and for
the automatic sky method (chosen for the whole frame, not the band); bad ranges are
refused naming "rows"."""
import json

import numpy as np
import pytest

import welkin


def scene(method, aerial):
    d = {"version": 1, "atmosphere": "hazy", "sun": {"elevation_deg": 6, "azimuth_deg": 5},
         "method": method,
         "camera": {"matrix_world": [[0, 0, -1, 0], [-1, 0, 0, 0], [0, 1, 0, 50], [0, 0, 0, 1]],
                    "type": "PERSP", "lens_mm": 30},
         "resolution": {"x": 96, "y": 70, "percentage": 100}, "aerial": {"method": aerial}}
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
