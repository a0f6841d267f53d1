# SPDX-License-Identifier: Apache-2.0
"""welkin.aerial_table, welkin.aerial_screen_table and the add-on's images of them
(addon/welkin/aerial_table.py).

The table read as the material node group reads it (aerial_table.lookup: texel centres,
bilinear, two slices mixed in distance) against the core's per-pixel march
(welkin.aerial_perspective, method "raymarch") at the same pixels' directions and
distances, in hazy air, looking towards and away from the sun: in-scattering within 1 %
and transmittance within 0.005 over depths from 50 m to 40 km; the same for the screen
table (aerial_table.screen_lookup, what the Cycles group computes from the View Vector or
the Window coordinate and View Distance), also for an orthographic camera; the screen
table's lattice reads back its own entries and wraps without mixing the ends. Plus the closed forms:
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
    return json.dumps(
        {
            "version": 1,
            "atmosphere": "hazy",
            "sun": {"elevation_deg": 8, "azimuth_deg": sun_azimuth_deg},
            "resolution": {"x": W, "y": H, "percentage": 100},
            "camera": camera,
        }
    )


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
    print(
        f"{label}: L max rel {rel.max():.4f} mean {rel.mean():.5f}, T max abs {np.abs(T - T_ref).max():.5f}"
    )
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
    t = welkin.aerial_table(
        desc,
        azimuths=tab.AZIMUTHS,
        elevations=tab.ELEVATIONS,
        slices=tab.SLICES,
        max_distance_m=d_max,
        steps_per_slice=tab.STEPS_PER_SLICE,
    )
    atlas = tab.atlas_pixels(t["inscatter"], t["optical_depth"])
    direction, per = rays(desc)
    ground = np.isfinite(z)
    L, T = tab.lookup(atlas, direction[ground], (z * per)[ground], d_max)
    check_against_march(f"sun azimuth {sun_azimuth_deg}", L, T, L_ref[ground], T_ref[ground])
    check_far_is_hazed(z[ground], L, T)


def test_a_camera_that_sees_100_m_is_hazed():
    """Blender's default camera (Clip End 100 m) gives a table whose last slice is at 100 m,
    less than the 200 m of two linear distances: the slices are then about evenly spaced,
    and the table read as the shader still matches the march at every depth it sees."""
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    d_max = tab.max_distance_m(100.0, 6360e3, 6460e3)
    assert d_max == 100.0
    direction, per = rays(desc)
    # Every surface within the camera's 100 m along its ray (the depth is along the view axis).
    z0 = depth_image()
    z = np.where(np.isfinite(z0), np.minimum(z0, d_max / per), np.inf).astype(np.float32)
    L_ref, T_ref = welkin.aerial_perspective(desc, z, method="raymarch")
    t = welkin.aerial_table(
        desc,
        azimuths=tab.AZIMUTHS,
        elevations=tab.ELEVATIONS,
        slices=tab.SLICES,
        max_distance_m=d_max,
        steps_per_slice=tab.STEPS_PER_SLICE,
    )
    atlas = tab.atlas_pixels(t["inscatter"], t["optical_depth"])
    ground = np.isfinite(z)
    L, T = tab.lookup(atlas, direction[ground], (z * per)[ground], d_max)
    check_against_march("clip end 100 m", L, T, L_ref[ground], T_ref[ground])
    # Not vacuous: 100 m of hazy air dims the surface and adds light.
    assert T_ref[ground].min() < 0.99 and L[(z * per)[ground] > 90.0].min() > 0.0


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


@pytest.mark.parametrize(
    "field,value",
    [
        ("azimuths", 2),
        ("elevations", 1),
        ("slices", 1),
        ("max_distance_m", 0.0),
        ("steps_per_slice", 0),
        ("max_distance_m", float("nan")),
    ],
)
def test_bad_parameters_name_themselves(field, value):
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    kw = dict(azimuths=8, elevations=5, slices=4, max_distance_m=9000.0)
    kw[field] = value
    with pytest.raises(ValueError, match=field):
        welkin.aerial_table(desc, **kw)


# --- the screen table (Cycles' form) ----------------------------------------------------------


def screen_table(desc, coordinate, width=W, height=H, **kw):
    margin_x, margin_y = tab.screen_margins(width, height, 1.5)
    t = welkin.aerial_screen_table(
        desc,
        coordinate=coordinate,
        columns=tab.SCREEN_COLUMNS,
        rows=tab.SCREEN_ROWS,
        margin_x=margin_x,
        margin_y=margin_y,
        ratio=tab.SCREEN_RATIO,
        steps_per_slice=tab.SCREEN_STEPS_PER_SLICE,
        **kw,
    )
    return tab.ScreenLattice(t["lattice"]), t["textures"], t


def window(shape_hw):
    """Blender's Window coordinate of every pixel centre: u left to right, v bottom to top."""
    j, i = np.mgrid[0 : shape_hw[0], 0 : shape_hw[1]]
    return (i + 0.5) / shape_hw[1], 1.0 - (j + 0.5) / shape_hw[0]


def view_vectors(desc_json, direction):
    """Cycles' View Vector (camera space: x right, y up, z forward) of world directions."""
    m = np.array(json.loads(desc_json)["camera"]["matrix_world"])[:3, :3]
    right, up, back = m[:, 0], m[:, 1], m[:, 2]
    return direction @ right, direction @ up, -(direction @ back)


def coordinate_of(coordinate, desc_json, direction, shape_hw):
    if coordinate == "window":
        return window(shape_hw)
    x, y, _z = view_vectors(desc_json, direction)
    return x, y


@pytest.mark.parametrize("coordinate", ["view_vector", "window"])
@pytest.mark.parametrize("sun_azimuth_deg", [30.0, 180.0])
def test_screen_table_read_as_the_shader_matches_the_per_pixel_march(sun_azimuth_deg, coordinate):
    """The screen table through screen_lookup (what the Cycles node group computes from the
    View Vector or the Window coordinate and View Distance) against the per-pixel march: L
    within 1 %, T within 0.005, over 50 m to 40 km and the whole frame."""
    text = scene(sun_azimuth_deg)
    desc = welkin.SceneDescription.from_json_string(text)
    z = depth_image()
    L_ref, T_ref = welkin.aerial_perspective(desc, z, method="raymarch")
    lattice, images, _ = screen_table(desc, coordinate)
    direction, per = rays(desc)
    x, y = coordinate_of(coordinate, text, direction, z.shape)
    ground = np.isfinite(z)
    L, T = tab.screen_lookup(lattice, images, x[ground], y[ground], (z * per)[ground])
    check_against_march(
        f"screen table ({coordinate}, {lattice.slices} slices), sun azimuth {sun_azimuth_deg}",
        L,
        T,
        L_ref[ground],
        T_ref[ground],
    )
    check_far_is_hazed(z[ground], L, T)


def test_screen_table_of_an_orthographic_camera_measures_from_its_plane():
    """An orthographic camera's rays start across its plane, and Blender's View Z Depth (what
    the group reads for it) is the distance along them: the table matches the march."""
    d = json.loads(scene(30.0, height_m=200.0, pitch_deg=20.0))
    d["camera"].update(type="ORTHO", ortho_scale=3000.0)
    desc = welkin.SceneDescription.from_json_string(json.dumps(d))
    z = np.full((H, W), 1.0, np.float32) * np.linspace(300.0, 30e3, W, dtype=np.float32)[None, :]
    L_ref, T_ref = welkin.aerial_perspective(desc, z, method="raymarch")
    lattice, images, _ = screen_table(desc, "window")
    u, v = window(z.shape)
    L, T = tab.screen_lookup(lattice, images, u, v, z)
    check_against_march("orthographic", L, T, L_ref, T_ref)
    # Not vacuous: the rays' origins differ across the frame (3 km wide), and so does L.
    assert L_ref[:, -1].std() > 0.01 * L_ref[:, -1].mean()
    with pytest.raises(ValueError, match="coordinate"):
        screen_table(desc, "view_vector")


@pytest.mark.parametrize("coordinate", ["view_vector", "window"])
def test_screen_lattice_closed_forms(coordinate):
    text = scene(30.0)
    desc = welkin.SceneDescription.from_json_string(text)
    lattice, images, t = screen_table(desc, coordinate, unit_m=0.5)
    g = t["lattice"]
    C, R, S = lattice.columns, lattice.rows, lattice.slices
    assert images.shape == (3, S * R, C, 4) and t["inscatter"].shape == (S, R, C, 3)
    # The lattice covers the frame widened by the margins with C - 2 and R - 2 spacings, the
    # first point at or before the widened frame's first edge.
    margin_x, margin_y = tab.screen_margins(W, H, 1.5)
    edge_x, edge_y = np.meshgrid(
        np.linspace(-margin_x, 1 + margin_x, 65), np.linspace(-margin_y, 1 + margin_y, 65)
    )
    if coordinate == "window":
        xs, ys = edge_x, edge_y
    else:
        d = np.array([desc.camera_ray(a, 1.0 - b)[1] for a, b in zip(edge_x.ravel(), edge_y.ravel())])
        xs, ys, _z = view_vectors(text, d)
    x0, y0 = (g["first_x"] + 0.5) * g["spacing_x"], (g["first_y"] + 0.5) * g["spacing_y"]
    assert x0 <= xs.min() and x0 + (C - 1) * g["spacing_x"] >= xs.max()
    assert y0 <= ys.min() and y0 + (R - 1) * g["spacing_y"] >= ys.max()
    assert math.isclose((C - 2) * g["spacing_x"], (xs.max() - xs.min()) * 1.002, rel_tol=0.01)
    # Slices: integer powers of the ratio in the unit, one beyond each end of the distances
    # seen: the clip start (0.1 m) and the clip end (1e6 m) along the most oblique ray.
    unit, r, e = 0.5, lattice.ratio, lattice.first_exponent
    assert unit * r ** (e + 1) <= 0.1 and unit * r ** (e + S - 2) >= 1e6
    # Read as the shader reads them, at the lattice's own points and slices the textures give
    # back the table's entries exactly (texel centres: no filtering), wrap or no wrap.
    k, j, i = np.meshgrid(np.arange(S), np.arange(R), np.arange(C), indexing="ij")
    d = r ** (e + k.astype(np.float64))
    x, y = (g["first_x"] + i + 0.5) * g["spacing_x"], (g["first_y"] + j + 0.5) * g["spacing_y"]
    L, T = tab.screen_lookup(lattice, images, x, y, d)
    assert np.allclose(L, t["inscatter"], rtol=1e-4, atol=1e-6)
    assert np.allclose(T, t["transmittance"], atol=1e-5)
    # Halfway between slices, linearly in log d.
    mid = tab.screen_lookup(lattice, images, x[:-1], y[:-1], d[:-1] * math.sqrt(r))[0]
    assert np.allclose(mid, 0.5 * (t["inscatter"][:-1] + t["inscatter"][1:]), rtol=1e-4, atol=1e-6)
    # Every texel is some entry's: the placement is a bijection.
    placed = np.zeros((S * R, C), bool)
    rows = (k * R + g["first_y"] + j + e * R) % (S * R)
    placed[rows, (g["first_x"] + i) % C] = True
    assert placed.all()
    # T falls and L grows with distance along every ray, within 50 km (beyond, where T is a
    # few per cent, its Rec.709 blue is not monotonic: the spectrum's conversion has
    # negative lobes).
    within = unit * r ** (e + np.arange(S)) <= 50e3
    assert (np.diff(t["transmittance"][within], axis=0) <= 1e-7).all()
    # (L's sum may fall by the rounding of its three float channels where the air adds
    # nothing: a few units in the last place.)
    brightness = t["inscatter"].sum(-1)
    assert (np.diff(brightness, axis=0) >= -4 * np.spacing(brightness[1:])).all()


def test_screen_table_ends_read_their_own_slices():
    """A surface at the clip start and one at the clip end on the frame's most oblique ray
    read the slices beside them, not the other end's across the wrap."""
    text = scene(30.0)
    desc = welkin.SceneDescription.from_json_string(text)
    lattice, images, t = screen_table(desc, "view_vector")
    o, corner, per = desc.camera_ray(1.0, 1.0)
    x, y, _z = view_vectors(text, np.array([corner]))
    for distance in (0.1, 1e6 * per):
        L, T = tab.screen_lookup(lattice, images, x, y, np.array([distance]))
        z = np.full((H, W), np.inf, np.float32)
        z[-1, -1] = distance / desc.camera_ray((W - 0.5) / W, (H - 0.5) / H)[2]
        L_ref, T_ref = welkin.aerial_perspective(desc, z, method="raymarch")
        if distance < 1.0:  # 10 cm of air: nothing, not 1000 km of it
            assert (T[0] > 0.9999).all() and (L[0] < 1e-4 * t["inscatter"][-1].max()).all(), (T, L)
        else:
            assert (np.abs(T[0] - T_ref[-1, -1]) < 0.005).all(), (T, T_ref[-1, -1])
            assert (np.abs(L[0] - L_ref[-1, -1]) < 0.02 * L_ref[-1, -1]).all(), (L, L_ref[-1, -1])


@pytest.mark.parametrize(
    "field,value",
    [
        ("columns", 3),
        ("rows", 3),
        ("unit_m", 0.0),
        ("ratio", 1.0),
        ("margin_x", -0.1),
        ("steps_per_slice", 0),
        ("max_slices", 4),
        ("unit_m", float("nan")),
        ("coordinate", "screen"),
    ],
)
def test_screen_table_bad_parameters_name_themselves(field, value):
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    kw = dict(columns=4, rows=4)
    kw[field] = value
    with pytest.raises(ValueError, match=field):
        welkin.aerial_screen_table(desc, **kw)


def test_screen_table_keeps_to_max_slices():
    desc = welkin.SceneDescription.from_json_string(scene(30.0))
    t = welkin.aerial_screen_table(desc, columns=4, rows=4, max_slices=40)
    g = t["lattice"]
    assert g["slices"] <= 40 and g["ratio"] > 1.15
    assert 1.0 * g["ratio"] ** (g["first_exponent"] + 1) <= 0.1
    assert g["ratio"] ** (g["first_exponent"] + g["slices"] - 2) >= 1e6
