# SPDX-License-Identifier: Apache-2.0
"""The cloud bindings: welkin.CloudLayer, welkin.VdbClouds (with a VDB written by
pyopenvdb), welkin.cloud_radiance and welkin.sky_image(clouds=...)."""

import math

import numpy as np
import pytest

import welkin

openvdb = pytest.importorskip("pyopenvdb")


def write_ball(path, name="density", radius=8, voxel=10.0):
    grid = openvdb.FloatGrid()
    grid.name = name
    grid.transform = openvdb.createLinearTransform(voxelSize=voxel)
    acc = grid.getAccessor()
    for i in range(-radius, radius + 1):
        for j in range(-radius, radius + 1):
            for k in range(-radius, radius + 1):
                r = math.sqrt(i * i + j * j + k * k) / radius
                if r < 1.0:
                    acc.setValueOn((i, j, k), 1.0 - r * r)
    openvdb.write(str(path), grids=[grid])


def test_vdb_clouds_with_blender_matrix(tmp_path):
    path = tmp_path / "ball.vdb"
    write_ball(path)
    # Blender's matrix_world, [row][column]: a translation in the last column.
    m = np.eye(4)
    m[:3, 3] = (0.0, 1000.0, 500.0)
    v = welkin.VdbClouds(str(path), matrix_world=m, density_scale=0.02)
    assert v.active_voxel_count > 0 and v.negative_voxel_count == 0 and v.warning == ""
    # The default placement is Blender's: voxel (0, 0, 0), value 1, sits at index
    # (1/2, 1/2, 1/2), i.e. half a voxel (5 m) further along each axis than OpenVDB's
    # convention puts it; placement="openvdb" puts it at the object's origin.
    s = v.sigma_t(np.array([[5.0, 1005.0, 505.0], [0.0, 1000.0, 500.0], [0.0, 0.0, 0.0]]))
    assert s[0] == pytest.approx(0.02, rel=1e-6) and s[1] < 0.02 * (1.0 - 1e-3) and s[2] == 0.0
    o = welkin.VdbClouds(str(path), matrix_world=m, density_scale=0.02, placement="openvdb")
    s = o.sigma_t(np.array([[0.0, 1000.0, 500.0], [5.0, 1005.0, 505.0]]))
    assert s[0] == pytest.approx(0.02, rel=1e-6) and s[1] < 0.02 * (1.0 - 1e-3)
    (lo_b, hi_b), (lo_o, hi_o) = v.bounds_m, o.bounds_m
    assert np.allclose(np.subtract(lo_b, lo_o), 5.0) and np.allclose(np.subtract(hi_b, hi_o), 5.0)
    atm = welkin.Atmosphere.preset("bruneton2017")
    d = np.array([[0.0, 1000.0, 500.0]]) / math.hypot(1000.0, 500.0)
    L, T, depth = welkin.cloud_radiance(v, atm, 0.0, (0.3, 0.2, 0.9), d)
    assert L.shape == (1, len(atm.wavelengths_nm)) and T.shape == (1,)
    assert 0.0 < T[0] < 1.0 and np.all(L > 0.0)
    assert abs(depth[0] - math.hypot(1000.0, 500.0)) < 80.0


def test_cloud_radiance_takes_the_scene_files_lighting_options(tmp_path):
    """`lighting` is the scene file's clouds.lighting: keys that are also keywords give the
    same march as the keywords; {"sides": False} takes away the diffuse light's leak
    through the cloud's sides, which only removes light (it adds the leak to the slab's
    absorption), so a dense ball is brighter without it; bad keys and values are named as
    in a scene file."""
    path = tmp_path / "ball.vdb"
    write_ball(path, radius=12, voxel=25.0)
    m = np.eye(4)
    m[:3, 3] = (0.0, 2000.0, 400.0)
    v = welkin.VdbClouds(str(path), matrix_world=m, density_scale=0.05)
    atm = welkin.Atmosphere.preset("bruneton2017")
    a = np.radians(np.linspace(-4.0, 4.0, 9))
    e = math.atan2(400.0, 2000.0) + np.radians(np.linspace(-4.0, 4.0, 9))
    az, el = np.meshgrid(a, e)
    d = np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], -1).reshape(-1, 3)
    sun = (0.8, 0.0, 0.6)  # from the side: a sunlit and a shadow half
    keywords = welkin.cloud_radiance(v, atm, 0.0, sun, d, max_steps=48, light_steps=6)
    options = welkin.cloud_radiance(v, atm, 0.0, sun, d, lighting={"max_steps": 48, "light_steps": 6})
    for x, y in zip(keywords, options):
        assert np.array_equal(x, y)
    with_sides = welkin.cloud_radiance(v, atm, 0.0, sun, d)[0].sum()
    without = welkin.cloud_radiance(v, atm, 0.0, sun, d, lighting={"sides": False})[0].sum()
    print(f"without the sides over with them: {without / with_sides:.3f}")
    assert with_sides > 0.0 and without > 1.05 * with_sides
    for bad, name in (
        ({"side": False}, "clouds.lighting.side"),
        ({"sides": 3}, "clouds.lighting.sides"),
        ({"max_steps": 0}, "clouds.lighting.max_steps"),
        ({"surface_cut": 0}, "clouds.lighting.surface_cut"),
        ({"surface_cut": 65}, "clouds.lighting.surface_cut"),
        ([1], "lighting"),
    ):
        with pytest.raises(ValueError, match=name):
            welkin.cloud_radiance(v, atm, 0.0, sun, d, lighting=bad)
    with pytest.raises(ValueError, match="lighting"):
        welkin.cloud_radiance(v, atm, 0.0, sun, d, method="reference", paths=4, lighting={})


def test_vdb_errors_name_file_and_grid(tmp_path):
    with pytest.raises(OSError, match="missing.vdb"):
        welkin.VdbClouds(str(tmp_path / "missing.vdb"))
    path = tmp_path / "smoke.vdb"
    write_ball(path, name="smoke")
    with pytest.raises(ValueError, match="no grid 'density'.*'smoke'"):
        welkin.VdbClouds(str(path))
    assert welkin.VdbClouds(str(path), grid="smoke").active_voxel_count > 0
    with pytest.raises(ValueError, match="matrix_world"):
        welkin.VdbClouds(str(path), grid="smoke", matrix_world=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="negative"):
        welkin.VdbClouds(str(path), grid="smoke", negative="maybe")
    with pytest.raises(ValueError, match="placement"):
        welkin.VdbClouds(str(path), grid="smoke", placement="cycles")


def test_cloud_types_are_presets_and_bad_names_list_them():
    assert welkin.CLOUD_TYPES == ["cumulus", "stratocumulus", "altocumulus", "stratus", "cirrus"]
    for name in welkin.CLOUD_TYPES:
        preset = welkin.cloud_type_preset(name)
        layer = welkin.CloudLayer(cloud_type=name)
        assert layer.cloud_type == name
        assert layer.bottom_altitude_m == preset["bottom_altitude_m"]
        assert layer.coverage == preset["coverage"]
    # A value given overrides the preset's.
    assert welkin.CloudLayer(cloud_type="cirrus", coverage=0.2).coverage == 0.2
    assert welkin.cloud_type_preset("cirrus")["bottom_altitude_m"] > 6000.0
    with pytest.raises(ValueError, match="cloud_type.*cumulus.*stratocumulus.*altocumulus.*stratus.*cirrus"):
        welkin.CloudLayer(cloud_type="nimbostratus")
    with pytest.raises(ValueError, match="cloud_type"):
        welkin.cloud_type_preset("Cumulus ")
    with pytest.raises(ValueError, match="coverage"):
        welkin.CloudLayer(cloud_type="stratus", coverage=-0.1)


def test_cloud_layer_coverage_is_measured():
    layer = welkin.CloudLayer(coverage=0.3, coverage_measure="area")
    assert abs(layer.covered_fraction() - 0.3) < 0.02


def test_cloud_layer_dome_coverage_is_the_sky_seen_covered():
    # coverage_measure="dome", the default: the share of the sky dome a ground observer sees
    # covered (oktas / 8), measured on other observers and directions than the calibration's.
    layer = welkin.CloudLayer(cloud_type="altocumulus", coverage=0.5)
    assert abs(layer.dome_fraction(observers=16, directions=256) - 0.5) < 0.05
    # Seen from the ground the layer's sides fill the gaps: less area than dome covered.
    assert layer.covered_fraction() < 0.45
    with pytest.raises(ValueError, match="observers"):
        layer.dome_fraction(observers=0)
    with pytest.raises(ValueError, match="directions"):
        layer.dome_fraction(directions=10**6)
    with pytest.raises(ValueError, match="coverage_measure.*oktas"):
        welkin.CloudLayer(coverage_measure="oktas")
    scene = welkin.SceneDescription.from_json_string(
        '{"version": 1, "clouds": {"layers": [{"cloud_type": "cirrus", "coverage_measure": "area"}]}}'
    )
    assert '"coverage_measure": "area"' in scene.to_json_string()
    scene = welkin.SceneDescription.from_json_string('{"version": 1, "clouds": {"layers": [{}]}}')
    assert '"coverage_measure": "dome"' in scene.to_json_string()  # the default, written out
    with pytest.raises(ValueError, match=r"clouds\.layers\[0\]\.coverage_measure"):
        welkin.SceneDescription.from_json_string(
            '{"version": 1, "clouds": {"layers": [{"coverage_measure": "sky"}]}}'
        )


def test_cloud_layer_and_cloudy_sky_image():
    with pytest.raises(ValueError, match="coverage"):
        welkin.CloudLayer(coverage=2.0)
    layer = welkin.CloudLayer(coverage=0.7, density_per_m=0.01, seed=3)
    assert layer.coverage == 0.7
    atm = welkin.Atmosphere.preset("bruneton2017")
    sun = (0.6, 0.2, 0.5)
    clear = welkin.sky_image(atm, 0.0, sun, 32, output="spectral", sun_disc=False, ground=False)
    cloudy = welkin.sky_image(
        atm, 0.0, sun, 32, output="spectral", sun_disc=False, clouds=layer, ground=False
    )
    assert clear.shape == cloudy.shape == (16, 32, len(atm.wavelengths_nm))
    assert np.all(np.isfinite(cloudy))
    # The lower half looks at the ground below the layer: unchanged; the upper half changes.
    assert np.array_equal(clear[12:], cloudy[12:])
    assert np.abs(cloudy[:6] - clear[:6]).max() > 0.0
    rgb = welkin.sky_image(atm, 0.0, sun, 32, clouds=layer)
    assert rgb.shape == (16, 32, 3)
