"""welkin.aerial_table, welkin.aerial_screen_table and the add-on's images of them
(addon/welkin/aerial_table.py).

The table read as the material node group reads it (aerial_table.lookup: texel centres,
bilinear, two slices mixed in distance) against the core's per-pixel march
(welkin.aerial_perspective, method "raymarch") at the same pixels' directions and
distances, in hazy air, looking towards and away from the sun: in-scattering within 1 %
and transmittance within 0.005 over depths from 50 m to 40 km; the same for the screen
table (aerial_table.screen_lookup, what the Cycles group computes from the Window
coordinate and View Distance), also for an orthographic camera. Plus the closed forms:
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


def check_against_march(label, L, T, L_ref, T_ref):
    """L within 1 % of the march (relative, above 1e-3), T within 0.005."""
    rel = np.abs(L - L_ref) / np.maximum(L_ref, 1e-3)
    print(f"{label}: L max rel {rel.max():.4f} mean {rel.mean():.5f}, "
          f"T max abs {np.abs(T - T_ref).max():.5f}")
    assert rel.max() < 0.01
    assert np.abs(T - T_ref).max() < 0.005


def check_far_is_hazed(z, L, T):
    """Not vacuous: beyond 20 km T is well below 1, and L well above its value within 500 m."""
    far, near = z > 20e3, z < 500.0
    assert T[far].max() < 0.8 and L[far].mean() > 5.0 * L[near].mean()


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
    check_against_march(f"sun azimuth {sun_azimuth_deg}", L, T, L_ref[ground], T_ref[ground])
    check_far_is_hazed(z[ground], L, T)


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


# --- the screen table (Cycles' form) ----------------------------------------------------------

def screen_table(desc, layout, steps=tab.SCREEN_STEPS_PER_SLICE):
    t = welkin.aerial_screen_table(desc, columns=layout.columns, rows=layout.rows,
                                   slices=layout.slices, margin_x=layout.margin_x,
                                   margin_y=layout.margin_y, first_distance_m=layout.first_distance,
                                   ratio=layout.ratio, steps_per_slice=steps,
                                   first_index=layout.first_exponent)
    return t["textures"], t


def window(shape_hw):
    """Blender's Window coordinate of every pixel centre: u left to right, v bottom to top."""
    j, i = np.mgrid[0:shape_hw[0], 0:shape_hw[1]]
    return (i + 0.5) / shape_hw[1], 1.0 - (j + 0.5) / shape_hw[0]


@pytest.mark.parametrize("sun_azimuth_deg", [30.0, 180.0])
def test_screen_table_read_as_the_shader_matches_the_per_pixel_march(sun_azimuth_deg):
    """The screen table through screen_lookup (what the Cycles node group computes from the
    Window coordinate and View Distance) against the per-pixel march: L within 1 %, T within
    0.005, over 50 m to 40 km and the whole frame."""
    desc = welkin.SceneDescription.from_json_string(scene(sun_azimuth_deg))
    z = depth_image()
    L_ref, T_ref = welkin.aerial_perspective(desc, z, method="raymarch")
    layout = tab.ScreenLayout(W, H, 1.5, 0.1, 1e6)
    images, _ = screen_table(desc, layout)
    _direction, per = rays(desc)
    u, v = window(z.shape)
    ground = np.isfinite(z)
    L, T = tab.screen_lookup(layout, images, u[ground], v[ground], (z * per)[ground])
    check_against_march(f"screen table ({layout.slices} slices), sun azimuth {sun_azimuth_deg}",
                        L, T, L_ref[ground], T_ref[ground])
    check_far_is_hazed(z[ground], L, T)


def test_screen_table_of_an_orthographic_camera_measures_from_its_plane():
    """An orthographic camera's rays start across its plane, and Blender's View Z Depth (what
    the group reads for it) is the distance along them: the table matches the march."""
    d = json.loads(scene(30.0, height_m=200.0, pitch_deg=20.0))
    d["camera"].update(type="ORTHO", ortho_scale=3000.0)
    desc = welkin.SceneDescription.from_json_string(json.dumps(d))
    z = np.full((H, W), 1.0, np.float32) * np.linspace(300.0, 30e3, W, dtype=np.float32)[None, :]
    L_ref, T_ref = welkin.aerial_perspective(desc, z, method="raymarch")
    layout = tab.ScreenLayout(W, H, 1.5, 0.1, 1e6)
    images, _ = screen_table(desc, layout)
    u, v = window(z.shape)
    L, T = tab.screen_lookup(layout, images, u, v, z)
    check_against_march("orthographic", L, T, L_ref, T_ref)
    # Not vacuous: the rays' origins differ across the frame (3 km wide), and so does L.
    assert L_ref[:, -1].std() > 0.01 * L_ref[:, -1].mean()


def test_screen_layout_closed_forms():
    layout = tab.ScreenLayout(480, 270, 1.5, 0.1, 1e6)
    # The slices are integer powers of the ratio: the first at or below clip end / 1e5, the
    # last at or beyond clip end, so that floor(log_ratio d) is the slice for every d drawn.
    assert layout.first_distance <= 1e6 / tab.SCREEN_RANGE < layout.first_distance * layout.ratio
    assert layout.first_distance * layout.ratio ** (layout.slices - 1) >= 1e6
    ax, bx, ay, by = layout.affine()
    # The frame's edges, widened by the margin, land on the first and last texel centres of
    # slice 0's tile, and every slice's tile is `rows` rows.
    C, R, S = layout.columns, layout.rows, layout.slices
    assert math.isclose(ax * -layout.margin_x + bx, 0.5 / C)
    assert math.isclose(ax * (1 + layout.margin_x) + bx, 1 - 0.5 / C)
    assert math.isclose(ay * -layout.margin_y + by, 0.5 / (R * S))
    assert math.isclose(ay * (1 + layout.margin_y) + by, (R - 0.5) / (R * S))
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    layout = tab.ScreenLayout(W, H, 1.5, 1.0, 1e4)
    images, t = screen_table(desc, layout)
    k = 20
    dk = layout.first_distance * layout.ratio ** k
    # At a slice's distance t is the slice's index (first_exponent + k) and value + t step is
    # the slice's own L (1 - T); the steps are the differences to the next slice, 0 in slice
    # 0 and the last.
    _x, _y, t_k = tab.screen_coordinates(layout, np.array([0.6]), np.array([0.4]), np.array([dk]))
    assert abs(t_k[0] - (layout.first_exponent + k)) < 1e-6
    row = k * layout.rows  # tile k's first row
    for value, step, table in ((0, 1, t["inscatter"]), (2, 3, 1.0 - t["transmittance"])):
        assert np.allclose(images[step][row + 3, 5, :3],
                           table[k + 1, layout.rows - 4, 5] - table[k, layout.rows - 4, 5], atol=1e-6)
        at_k = images[value][row + 3, 5, :3] + (layout.first_exponent + k) * images[step][row + 3, 5, :3]
        assert np.allclose(at_k, table[k, layout.rows - 4, 5], rtol=1e-5, atol=1e-6)
        assert (images[step][:layout.rows, :, :3] == 0).all()
        assert (images[step][-layout.rows:, :, :3] == 0).all()
    assert (images[..., 3] == 1).all()
    # T falls and L grows with distance along every ray.
    assert (np.diff(t["transmittance"], axis=0) <= 1e-7).all()
    assert (np.diff(t["inscatter"].sum(-1), axis=0) > 0).all()


@pytest.mark.parametrize("field,value", [("columns", 1), ("rows", 1), ("slices", 1),
                                         ("first_distance_m", 0.0), ("ratio", 1.0),
                                         ("margin_x", -0.1), ("steps_per_slice", 0),
                                         ("first_distance_m", float("nan"))])
def test_screen_table_bad_parameters_name_themselves(field, value):
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    kw = dict(columns=4, rows=3, slices=5, first_distance_m=10.0)
    kw[field] = value
    with pytest.raises(ValueError, match=field):
        welkin.aerial_screen_table(desc, **kw)


def test_screen_layout_rejects_a_bad_clip_range():
    with pytest.raises(ValueError, match="clip range"):
        tab.ScreenLayout(64, 36, 1.5, 10.0, 1.0)
