# SPDX-License-Identifier: Apache-2.0
"""welkin.scene_sky_image keeps the clouds' view samples of its last cloudy sky
(keep_cloud_samples, clouds/lighting.hpp CloudViewCache): a call whose scene differs only in
its sun lights them again, and must give the image a fresh march gives, bit for bit; a scene
that differs in anything else, or a VDB file written again under the same name, must be
marched afresh, not lit from the old samples."""

import json
import os

import numpy as np
import pytest

import welkin

openvdb = pytest.importorskip("pyopenvdb")

WIDTH = 96


def scene(elevation_deg, azimuth_deg=90.0, **clouds):
    e, a = np.radians(elevation_deg), np.radians(azimuth_deg)
    s = [float(np.cos(e) * np.cos(a)), float(np.cos(e) * np.sin(a)), float(np.sin(e))]
    return json.dumps({"version": 1, "sun": {"direction": s}, "clouds": clouds})


def sky(text, keep=True):
    return welkin.scene_sky_image(text, WIDTH, keep_cloud_samples=keep)


def fresh(text):
    return sky(text, keep=False)


@pytest.mark.parametrize("cloud_type", ["altocumulus", "cirrus"])
def test_the_sun_turned_is_a_fresh_march(cloud_type):
    layers = {"layers": [{"cloud_type": cloud_type}]}
    first = sky(scene(35.0, **layers))
    turned = scene(12.0, 150.0, **layers)
    again = sky(turned)
    assert np.array_equal(again, fresh(turned))
    assert not np.array_equal(again, first)  # the light did change
    # A third sun, from the samples of the two before.
    low = scene(3.0, 250.0, **layers)
    assert np.array_equal(sky(low), fresh(low))


def test_another_layer_is_marched_afresh():
    sky(scene(30.0, layers=[{"cloud_type": "cumulus", "coverage": 0.3}]))
    other = scene(30.0, layers=[{"cloud_type": "cumulus", "coverage": 0.6}])
    assert np.array_equal(sky(other), fresh(other))
    moved = scene(30.0, layers=[{"cloud_type": "cumulus", "coverage": 0.6, "wind_offset_m": [900.0, 0.0]}])
    assert np.array_equal(sky(moved), fresh(moved))


def write_ball(path, value):
    grid = openvdb.FloatGrid()
    grid.name = "density"
    grid.transform = openvdb.createLinearTransform(voxelSize=40.0)
    acc = grid.getAccessor()
    for i in range(-10, 11):
        for j in range(-10, 11):
            for k in range(-6, 7):
                r2 = (i * i + j * j) / 100.0 + k * k / 36.0
                if r2 < 1.0:
                    acc.setValueOn((i, j, k), value * (1.0 - r2))
    openvdb.write(str(path), grids=[grid])


def test_a_vdb_written_again_is_marched_afresh(tmp_path):
    path = tmp_path / "cloud.vdb"
    m = [[1, 0, 0, 0], [0, 1, 0, 1500], [0, 0, 1, 1200], [0, 0, 0, 1]]
    volumes = [{"file": str(path), "matrix_world": m, "density_scale": 0.05}]
    write_ball(path, 1.0)
    text = scene(30.0, volumes=volumes)
    before = sky(text)
    stamp = os.stat(path)
    write_ball(path, 0.2)  # the same name, another cloud (another size's not needed: its time)
    os.utime(path, ns=(stamp.st_atime_ns, stamp.st_mtime_ns + 1_000_000))
    after = sky(text)
    assert np.array_equal(after, fresh(text))
    assert not np.array_equal(after, before)


def test_a_preview_and_its_sky_each_keep_their_own():
    # The add-on's live update renders a preview (256 wide) and then the full sky after each
    # lamp rotation: two keys in turn, each lit again from its own samples.
    layers = {"layers": [{"cloud_type": "stratocumulus"}]}
    for elevation in (40.0, 25.0, 10.0):
        text = scene(elevation, **layers)
        preview = welkin.scene_sky_image(text, WIDTH // 2)
        assert np.array_equal(preview, welkin.scene_sky_image(text, WIDTH // 2, keep_cloud_samples=False))
        assert np.array_equal(sky(text), fresh(text))


def test_a_cancelled_sky_leaves_samples_that_still_hold():
    # A sky cancelled part-way keeps whole rays only (a ray's samples are stored when its
    # march ends); the next one (the sun turned) lights those it finds and marches the rest:
    # still the fresh march.
    layers = {"layers": [{"cloud_type": "cirrus", "coverage": 0.5}]}
    fractions = []

    # Stopped at the first report past a quarter: the reports come a few per cent apart, but
    # on a loaded machine one can come a quarter later than the one before (measured with
    # the other core busy), and a stop asked for at 0.5 could come after the whole sky.
    def stop_at_a_quarter(f):
        fractions.append(f)
        return f < 0.25

    with pytest.raises(KeyboardInterrupt):
        welkin.scene_sky_image(scene(30.0, **layers), WIDTH * 2, progress=stop_at_a_quarter)
    assert 0.25 <= max(fractions) < 1.0
    turned = scene(18.0, 200.0, **layers)
    kept = welkin.scene_sky_image(turned, WIDTH * 2)
    assert np.array_equal(kept, welkin.scene_sky_image(turned, WIDTH * 2, keep_cloud_samples=False))
