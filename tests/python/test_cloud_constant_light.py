# SPDX-License-Identifier: Apache-2.0
"""welkin.cloud_radiance with a constant light (sun_irradiance, ambient_radiance): the
light a Cycles sun lamp and a uniform world give, so that Cycles can be compared with
both integrators (bench/cycles_clouds.py, tests/blender/test_cycles_clouds.py)."""

import math

import numpy as np
import pytest

import welkin

openvdb = pytest.importorskip("pyopenvdb")


def write_ball(path, radius=8, voxel=10.0):
    grid = openvdb.FloatGrid()
    grid.name = "density"
    grid.transform = openvdb.createLinearTransform(voxelSize=voxel)
    acc = grid.getAccessor()
    for i in range(-radius, radius + 1):
        for j in range(-radius, radius + 1):
            for k in range(-radius, radius + 1):
                r = math.sqrt(i * i + j * j + k * k) / radius
                if r < 1.0:
                    acc.setValueOn((i, j, k), 1.0 - r * r)
    openvdb.write(str(path), grids=[grid])


@pytest.fixture
def ball(tmp_path):
    path = tmp_path / "ball.vdb"
    write_ball(path)
    m = np.eye(4)
    m[:3, 3] = (0.0, 1000.0, 0.0)
    return welkin.VdbClouds(str(path), matrix_world=m, density_scale=0.03)


def views():
    # A fan of rays from the origin across the ball (centre 1000 m away, radius 80 m).
    x = np.linspace(-0.07, 0.07, 9)
    d = np.stack([x, np.ones_like(x), 0.3 * x], axis=1)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_uniform_sky_invariant(ball):
    # A conservative cloud (albedo 1) in a uniform isotropic sky of radiance L and no sun
    # sends exactly (1 - T) L towards every viewer (what the cloud removes from the
    # background it gives back from the sky). The march satisfies it by construction of
    # its sky term; the path tracer as an expectation: each path scatters at least once
    # with probability 1 - T and then escapes with L (albedo 1), so its estimate is
    # L x Binomial(paths, 1 - T) / paths, standard error L sqrt((1-T) T / paths).
    atm = welkin.Atmosphere.preset("bruneton2017")
    amb = np.array([2.0, 0.5])
    d = views()
    L, T, _ = welkin.cloud_radiance(
        ball, atm, 0.0, (0.3, 0.2, 0.9), d, sun_irradiance=[0.0, 0.0], ambient_radiance=amb
    )
    assert L.shape == (len(d), 2)
    assert 0.01 < T.min() and T.max() < 1.0 and T.min() < 0.6
    np.testing.assert_allclose(L, (1.0 - T)[:, None] * amb, rtol=1e-3, atol=1e-6)
    paths = 2048
    L, T, _ = welkin.cloud_radiance(
        ball,
        atm,
        0.0,
        (0.3, 0.2, 0.9),
        d,
        method="reference",
        paths=paths,
        sun_irradiance=[0.0, 0.0],
        ambient_radiance=amb,
    )
    se = np.sqrt(np.maximum((1.0 - T) * T, 1e-4) / paths)
    for c in range(2):
        assert np.all(np.abs(L[:, c] / amb[c] - (1.0 - T)) < 5.0 * se)


def test_constant_light_is_linear_and_independent_of_the_atmosphere(ball):
    d = views()
    sun = (0.3, -0.5, 0.8)
    a = welkin.cloud_radiance(
        ball,
        welkin.Atmosphere.preset("bruneton2017"),
        0.0,
        sun,
        d,
        sun_irradiance=[1.0],
        ambient_radiance=[0.1],
    )
    b = welkin.cloud_radiance(
        ball, welkin.Atmosphere.preset("hazy"), 3000.0, sun, d, sun_irradiance=[3.0], ambient_radiance=[0.3]
    )
    assert a[0].shape == (len(d), 1)
    np.testing.assert_allclose(b[0], 3.0 * a[0], rtol=1e-5, atol=1e-7)
    np.testing.assert_array_equal(a[1], b[1])
    # The sun alone lights the cloud: more light than the sky alone gives here.
    s = welkin.cloud_radiance(
        ball,
        welkin.Atmosphere.preset("bruneton2017"),
        0.0,
        sun,
        d,
        sun_irradiance=[1.0],
        ambient_radiance=[0.0],
    )
    assert np.all(s[0] > 0.0) and np.all(s[0] <= a[0] + 1e-7)


def test_constant_light_bad_input(ball):
    atm = welkin.Atmosphere.preset("bruneton2017")
    d = views()
    with pytest.raises(ValueError, match="ambient_radiance"):
        welkin.cloud_radiance(ball, atm, 0.0, (0, 0, 1), d, sun_irradiance=[1.0])
    with pytest.raises(ValueError, match="sun_irradiance"):
        welkin.cloud_radiance(ball, atm, 0.0, (0, 0, 1), d, ambient_radiance=[1.0])
    with pytest.raises(ValueError, match="ambient_radiance"):
        welkin.cloud_radiance(ball, atm, 0.0, (0, 0, 1), d, sun_irradiance=[1.0, 1.0], ambient_radiance=[1.0])
    with pytest.raises(ValueError, match="sun_irradiance"):
        welkin.cloud_radiance(ball, atm, 0.0, (0, 0, 1), d, sun_irradiance=[-1.0], ambient_radiance=[1.0])
    with pytest.raises(ValueError, match="sun_irradiance"):
        welkin.cloud_radiance(ball, atm, 0.0, (0, 0, 1), d, sun_irradiance=[[1.0]], ambient_radiance=[1.0])


def test_phase_parameters(ball):
    # One HG lobe given as the forward lobe (w_forward = 1) or as the back lobe
    # (w_forward = 0) is the same phase: the same numbers, seed for seed, both methods.
    atm = welkin.Atmosphere.preset("bruneton2017")
    d = views()
    sun = (0.3, -0.5, 0.8)
    for method in ("fast", "reference"):
        kw = dict(method=method, paths=64, sun_irradiance=[1.0], ambient_radiance=[0.1])
        a = welkin.cloud_radiance(ball, atm, 0.0, sun, d, g_forward=0.6, w_forward=1.0, **kw)
        b = welkin.cloud_radiance(ball, atm, 0.0, sun, d, g_back=0.6, w_forward=0.0, **kw)
        np.testing.assert_array_equal(a[0], b[0])
        # and the phase is used: the mirrored lobe gives other numbers.
        c = welkin.cloud_radiance(ball, atm, 0.0, sun, d, g_forward=-0.6, w_forward=1.0, **kw)
        assert not np.allclose(a[0], c[0])
    for name, value in (("g_forward", 1.0), ("g_back", -1.5), ("w_forward", 1.2)):
        with pytest.raises(ValueError, match=name):
            welkin.cloud_radiance(ball, atm, 0.0, sun, d, **{name: value})
    with pytest.raises(ValueError, match="ground_radiance"):
        welkin.cloud_radiance(ball, atm, 0.0, (0, 0, 1), d, ground_radiance=[1.0])
    with pytest.raises(ValueError, match="ground_radiance"):
        welkin.cloud_radiance(
            ball,
            atm,
            0.0,
            (0, 0, 1),
            d,
            sun_irradiance=[1.0],
            ambient_radiance=[1.0],
            ground_radiance=[1.0, 2.0],
        )
    with pytest.raises(ValueError, match=r"ground_radiance\[0\]"):
        welkin.cloud_radiance(
            ball, atm, 0.0, (0, 0, 1), d, sun_irradiance=[1.0], ambient_radiance=[1.0], ground_radiance=[-1.0]
        )


@pytest.mark.parametrize("method", ["fast", "reference"])
def test_sky_and_ground_add_up(ball, method):
    # The light is linear in the sky: a sky above the horizon only plus the ground below
    # only is the uniform sky, for both integrators (the reference's paths are the same
    # for the same seed; the march's mix of the two skies has weights that sum to 1), seen
    # from below the ball and from above it.
    atm = welkin.Atmosphere.preset("bruneton2017")
    kw = dict(method=method, paths=64, sun_irradiance=[0.0])
    for origin in ((0.0, 0.0, -300.0), (0.0, 0.0, 300.0)):
        aim = np.array([0.0, 1000.0, 0.0]) - np.array(origin)
        d = aim / np.linalg.norm(aim) + np.array([[0.0, 0.0, z] for z in (-0.02, 0.0, 0.02)])
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        sky, _, _ = welkin.cloud_radiance(
            ball, atm, 0.0, (0, 0, 1), d, origin=origin, ambient_radiance=[1.0], ground_radiance=[0.0], **kw
        )
        ground, _, _ = welkin.cloud_radiance(
            ball, atm, 0.0, (0, 0, 1), d, origin=origin, ambient_radiance=[0.0], ground_radiance=[1.0], **kw
        )
        both, _, _ = welkin.cloud_radiance(
            ball, atm, 0.0, (0, 0, 1), d, origin=origin, ambient_radiance=[1.0], **kw
        )
        np.testing.assert_allclose(sky + ground, both, rtol=1e-5, atol=1e-7)
        assert np.all(sky > 0.01) and np.all(ground > 0.01) and np.all(both > 0.05)
