"""welkin.aerial_table and the add-on's atlas of it (addon/welkin/aerial_table.py).

The table read as the material node group reads it (aerial_table.lookup: texel centres,
bilinear, two slices mixed in distance) against the core's per-pixel march
(welkin.aerial_perspective, method "raymarch") at the same pixels' directions and
distances, in hazy air, looking towards and away from the sun: in-scattering within 1 %
and transmittance within 0.005 over depths from 50 m to 40 km. Plus the closed forms:
distance 0 gives L = 0, T = 1 exactly; bad parameters get ValueError naming them.

Run with PYTHONPATH=build /usr/bin/python3 -m pytest tests/python/test_aerial_table.py.
"""
import json
import math

import numpy as np
import pytest

import welkin
from welkin_addon import aerial_table as tab

W, H = 64, 36


def scene(sun_azimuth_deg, height_m=30.0, pitch_deg=1.5):
    p = math.radians(pitch_deg)
    fwd, up, right = (math.cos(p), 0.0, -math.sin(p)), (math.sin(p), 0.0, math.cos(p)), (0.0, -1.0, 0.0)
    cols = [right, up, tuple(-v for v in fwd), (0.0, 0.0, height_m)]
    rows = [[cols[c][r] for c in range(4)] for r in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
    camera = {"matrix_world": rows, "type": "PERSP", "lens_mm": 30.0, "clip_end_m": 1e6}
    return json.dumps({"version": 1, "atmosphere": "hazy",
                       "sun": {"elevation_deg": 8, "azimuth_deg": sun_azimuth_deg},
                       "resolution": {"x": W, "y": H, "percentage": 100}, "camera": camera})


def depth_image():
    z = np.full((H, W), np.inf, np.float32)
    ground = np.arange(H // 3, H)
    f = (ground - H // 3) / (H - 1 - H // 3)
    z[ground, :] = (40e3 * np.exp(np.log(50.0 / 40e3) * f))[:, None]
    return z


def rays(desc):
    d = np.zeros((H, W, 3))
    per = np.zeros((H, W))
    for j in range(H):
        for i in range(W):
            _o, v, k = desc.camera_ray((i + 0.5) / W, (j + 0.5) / H)
            d[j, i], per[j, i] = v, k
    return d, per


@pytest.mark.parametrize("sun_azimuth_deg", [30.0, 180.0])
def test_table_read_as_the_shader_matches_the_per_pixel_march(sun_azimuth_deg):
    desc = welkin.SceneDescription.from_json_string(scene(sun_azimuth_deg))
    z = depth_image()
    L_ref, T_ref = welkin.aerial_perspective(desc, z, method="raymarch")
    d_max = tab.max_distance_m(1e6, 6360e3, 6460e3)
    t = welkin.aerial_table(desc, azimuths=tab.AZIMUTHS, elevations=tab.ELEVATIONS,
                            slices=tab.SLICES, max_distance_m=d_max,
                            steps_per_slice=tab.STEPS_PER_SLICE)
    atlas = tab.atlas_pixels(t["inscatter"], t["optical_depth"])
    direction, per = rays(desc)
    ground = np.isfinite(z)
    L, T = tab.lookup(atlas, direction[ground], (z * per)[ground], d_max)
    rel = np.abs(L - L_ref[ground]) / np.maximum(L_ref[ground], 1e-3)
    print(f"sun azimuth {sun_azimuth_deg}: L max rel {rel.max():.4f} mean {rel.mean():.5f}, "
          f"T max abs {np.abs(T - T_ref[ground]).max():.5f}")
    assert rel.max() < 0.01
    assert np.abs(T - T_ref[ground]).max() < 0.005
    # The far pixels are hazed (the test is not vacuous): T well below 1, L well above 0.
    far, near = z[ground] > 20e3, z[ground] < 500.0
    assert T[far].max() < 0.8 and L[far].mean() > 5.0 * L[near].mean()


def test_distance_zero_is_no_air_and_the_layout_is_the_documented_one():
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    t = welkin.aerial_table(desc, azimuths=8, elevations=5, slices=4, max_distance_m=9000.0)
    assert t["inscatter"].shape == (4, 5, 8, 3) and t["optical_depth"].shape == (4, 5, 8, 3)
    assert (t["inscatter"][0] == 0).all() and (t["optical_depth"][0] == 0).all()
    # Farther slices hold more air on every direction: tau grows with k.
    assert (np.diff(t["optical_depth"], axis=0) > 0).all()
    # Looking down (row 0, nadir) from 30 m the ray meets the ground's dense air at once;
    # looking up (last row, zenith) it thins: more optical depth below than above.
    assert (t["optical_depth"][1:, 0] > t["optical_depth"][1:, -1]).all()


@pytest.mark.parametrize("field,value", [("azimuths", 2), ("elevations", 1), ("slices", 1),
                                         ("max_distance_m", 0.0), ("steps_per_slice", 0),
                                         ("max_distance_m", float("nan"))])
def test_bad_parameters_name_themselves(field, value):
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    kw = dict(azimuths=8, elevations=5, slices=4, max_distance_m=9000.0)
    kw[field] = value
    with pytest.raises(ValueError, match=field):
        welkin.aerial_table(desc, **kw)
