# SPDX-License-Identifier: Apache-2.0
"""The add-on's Place and Time, Blender-free (addon/welkin/place_time.py): the moment from a
date and a keyable time, the scene's north, the lamp's rotation, and the moon lamp and the
world's moonlit sky against the CLI and the module's own moment image."""

import dataclasses
import datetime
import json
import math
import subprocess

import numpy as np
import pytest

import welkin
from welkin_addon import place_time, sky_compute, sky_request  # noqa: E402 (conftest loads it)

PARIS = place_time.PlaceTime(2026, 6, 21, 21.5, 2.0, 48.8566, 2.3522, 0.0, 0.0)
dataclass_with = dataclasses.replace


def test_iso_time_carries_hours_across_midnight_and_keeps_the_offset():
    assert place_time.iso_time(PARIS) == "2026-06-21T21:30:00.000000+02:00"
    late = place_time.iso_time(dataclass_with(PARIS, hours=25.25))
    assert late == "2026-06-22T01:15:00.000000+02:00"
    early = place_time.iso_time(dataclass_with(PARIS, hours=-0.5, utc_offset_h=-9.5))
    assert early == "2026-06-20T23:30:00.000000-09:30"
    # A keyframed time between whole seconds reaches the core to the microsecond.
    t = place_time.iso_time(dataclass_with(PARIS, hours=12.0 + 1.0 / 7200.0))
    assert datetime.datetime.fromisoformat(t).microsecond == 500000


@pytest.mark.parametrize(
    "changes, parameter",
    [
        ({"day": 31}, "date"),
        ({"month": 13}, "date"),
        ({"hours": math.nan}, "hours"),
        ({"hours": 1e6}, "hours"),
        ({"utc_offset_h": 15.0}, "utc_offset_h"),
        ({"north_deg": math.inf}, "north_deg"),
        ({"latitude_deg": 91.0}, "latitude"),
        ({"year": 1850}, "time"),
    ],
)
def test_bad_settings_name_the_parameter(changes, parameter):
    with pytest.raises(ValueError, match=parameter):
        place_time.bodies(welkin, dataclass_with(PARIS, **changes))


@pytest.mark.parametrize("north", [0.0, 30.0, -135.0, 270.0])
def test_bodies_are_the_cores_turned_to_the_scenes_north(north):
    b = place_time.bodies(welkin, dataclass_with(PARIS, north_deg=north))
    core = welkin.sun_and_moon("2026-06-21T21:30:00+02:00", 48.8566, 2.3522)
    assert b.place_and_time == core
    for name, d in (("sun", b.sun_direction), ("moon", b.moon_direction)):
        # Independently: north is (-sin N, cos N, 0), east (cos N, sin N, 0) in the scene.
        n = math.radians(north)
        d = np.asarray(d)
        azimuth = (
            math.degrees(
                math.atan2(d @ [math.cos(n), math.sin(n), 0.0], d @ [-math.sin(n), math.cos(n), 0.0])
            )
            % 360.0
        )
        assert abs((azimuth - core[name]["azimuth_deg"] + 180.0) % 360.0 - 180.0) < 1e-9
        assert place_time.azimuth_deg(d, north) == pytest.approx(core[name]["azimuth_deg"], abs=1e-9)
        assert math.degrees(math.asin(d[2])) == pytest.approx(core[name]["elevation_deg"], abs=1e-9)
    assert b.moon_irradiance_ratio == core["moon"]["irradiance_ratio"]


@pytest.mark.parametrize(
    "direction", [(0.3, -0.5, 0.8), (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (0.2, 0.9, -0.1)]
)
def test_lamp_euler_points_local_z_at_the_direction(direction):
    a, b, g = place_time.lamp_euler(direction)
    # Blender's XYZ Euler: R = Rz(g) Ry(b) Rx(a); the lamp's +Z is R's third column.
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(g), -math.sin(g), 0], [math.sin(g), math.cos(g), 0], [0, 0, 1]])
    d = np.asarray(direction) / np.linalg.norm(direction)
    assert np.allclose((rz @ ry @ rx)[:, 2], d, atol=1e-12)
    with pytest.raises(ValueError, match="direction"):
        place_time.lamp_euler((0.0, 0.0, 0.0))


def test_moon_lamp_is_the_clis_moon_light():
    from cli_testing import CLI

    done = subprocess.run(
        [CLI, "sun", "--latitude", "48.8566", "--longitude", "2.3522", "--time", "2026-06-21T21:30:00+02:00"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    cli = json.loads(done.stdout)
    b = place_time.bodies(welkin, PARIS)
    atm = sky_request.build_atmosphere(sky_request.SkyRequest(), welkin)
    lamp = place_time.moon_lamp(
        welkin, atm, 0.0, b.moon_direction, b.moon_irradiance_ratio, b.moon_angular_radius_rad, 1.0
    )
    assert np.allclose(
        np.asarray(lamp.color) * lamp.strength_w_m2,
        cli["moon_direct_irradiance_rgb_W_m2"],
        rtol=1e-5,
        atol=0.0,
    )
    assert lamp.angle_rad == pytest.approx(
        2.0 * math.radians(cli["place_and_time"]["moon"]["angular_radius_deg"]), rel=1e-12
    )
    # Exposure scales it as the sun lamp's.
    atm = sky_request.build_atmosphere(sky_request.SkyRequest(), welkin)
    bright = place_time.moon_lamp(
        welkin, atm, 0.0, b.moon_direction, b.moon_irradiance_ratio, b.moon_angular_radius_rad, 8.0
    )
    assert bright.strength_w_m2 == pytest.approx(8.0 * lamp.strength_w_m2, rel=1e-6)


@pytest.mark.parametrize("hours", [21.5, 23.75])  # dusk with the moon up; night
def test_world_sky_is_the_modules_moment_sky(hours):
    """The world image of a Place and Time request (north 0: the scene's frame is the
    core's) is welkin.sky_image_at's without the discs, to float rounding: the moonlit
    sky, the night sky's glow and the stars."""
    p = dataclass_with(PARIS, hours=hours)
    b = place_time.bodies(welkin, p)
    request = sky_request.SkyRequest(
        preset="bruneton2017",
        width=256,
        method="lut",
        sun_direction=b.sun_direction,
        moon_direction=b.moon_direction,
        moon_irradiance_ratio=b.moon_irradiance_ratio,
        night_sky=b.night_sky,
    )
    result = sky_compute.compute(welkin, request, disc=False)
    atm = sky_request.build_atmosphere(request, welkin)
    expected = welkin.sky_image_at(atm, place_time.iso_time(p), 48.8566, 2.3522, 256, "lut", discs=False)
    scale = float(expected.max())
    assert scale > 0.0
    assert np.abs(result.sky - expected).max() <= 1e-5 * scale
    # And the moon's part is there: without it the night sky is darker.
    moonless = sky_compute.compute(welkin, dataclass_with(request, moon_direction=()), disc=False)
    assert float(result.sky.mean()) > float(moonless.sky.mean())
    # The HDRI export adds it the same way (its sun disc off) and, with the discs, is the
    # module's moment image with both discs (the moon's with its phase).
    hdri = sky_compute.hdri(welkin, request, 256, sun_disc=False)
    assert np.abs(hdri - expected).max() <= 1e-5 * scale
    request = dataclasses.replace(
        request, moon_angular_radius_rad=b.moon_angular_radius_rad, sun_from_moon=b.sun_from_moon
    )
    hdri = sky_compute.hdri(welkin, request, 256)
    expected = welkin.sky_image_at(atm, place_time.iso_time(p), 48.8566, 2.3522, 256, "lut")
    assert np.allclose(hdri, expected, rtol=1e-5, atol=1e-5 * scale)


@pytest.mark.parametrize("width, north", [(256, 0.0), (2048, 30.0)])
def test_hdri_moon_disc_is_energy_exact(width, north):
    """At night (sun 12 degrees down: no sun disc) the HDRI's discs are the moon's alone:
    its pixels times their solid angles sum to the moon lamp's light (colour x strength,
    the moon being whole above the horizon), at any resolution and north."""
    b = place_time.bodies(welkin, dataclass_with(PARIS, hours=23.75, north_deg=north))
    assert b.sun_direction[2] < -0.2 and b.moon_direction[2] > 0.2
    request = sky_request.SkyRequest(
        width=256,
        method="lut",
        sun_direction=b.sun_direction,
        moon_direction=b.moon_direction,
        moon_irradiance_ratio=b.moon_irradiance_ratio,
        moon_angular_radius_rad=b.moon_angular_radius_rad,
        sun_from_moon=b.sun_from_moon,
    )
    disc = (
        sky_compute.hdri(welkin, request, width) - sky_compute.hdri(welkin, request, width, sun_disc=False)
    ).astype(np.float64)
    h = width // 2
    rows = np.arange(h)
    omega = (2.0 * np.pi / width) * (np.cos(np.pi * rows / h) - np.cos(np.pi * (rows + 1) / h))
    energy = (disc * omega[:, None, None]).sum(axis=(0, 1))
    atm = sky_request.build_atmosphere(request, welkin)
    lamp = place_time.moon_lamp(
        welkin, atm, 0.0, b.moon_direction, b.moon_irradiance_ratio, b.moon_angular_radius_rad, 1.0
    )
    assert np.allclose(energy, np.asarray(lamp.color) * lamp.strength_w_m2, rtol=1e-5, atol=0.0)


def test_world_stars_turn_with_the_scenes_north():
    """With the scene's north at 90 degrees (north is -X) the world's stars are the core's
    stars turned by 90 degrees about +Z: the image is the north-0 one rolled by a quarter
    of its width; Stars off leaves the glow alone."""
    images = []
    for north in (0.0, 90.0):
        b = place_time.bodies(welkin, dataclass_with(PARIS, hours=26.0, north_deg=north))
        request = sky_request.SkyRequest(
            preset="bruneton2017",
            width=256,
            method="lut",
            sun_direction=b.sun_direction,
            night_sky=b.night_sky,
        )
        no_stars = dataclasses.replace(request, night_sky=(*b.night_sky[:5], False))
        stars = (
            sky_compute.compute(welkin, request, disc=False).sky
            - sky_compute.compute(welkin, no_stars, disc=False).sky
        )
        assert float(stars.max()) > 0.0 and float(stars.min()) >= -1e-12
        images.append(stars)
    # u = 0.5 - atan2(y, x) / 2 pi: a turn by +90 degrees about +Z moves u by -1/4.
    rolled = np.roll(images[0], -256 // 4, axis=1)
    assert np.abs(rolled - images[1]).max() <= 1e-3 * float(images[0].max())


def test_request_rejects_a_bad_moon():
    with pytest.raises(ValueError, match="moon_direction"):
        sky_request.validate(
            sky_request.SkyRequest(moon_direction=(0.0, 0.0, 0.0), moon_irradiance_ratio=1e-7), welkin
        )
    with pytest.raises(ValueError, match="moon_irradiance_ratio"):
        sky_request.validate(
            sky_request.SkyRequest(moon_direction=(0.0, 0.0, 1.0), moon_irradiance_ratio=-1.0), welkin
        )


@pytest.mark.parametrize("hours, north", [(23.75, 0.0), (23.75, 30.0), (21.5, 0.0)])
def test_world_moon_disc_is_the_moon_lamps_light(hours, north):
    """The moon's disc the world's nodes draw (sky_compute.MoonDiscModel, welkin.moon_disc):
    its radiance, scale x the core's law (welkin.moon_disc_relative_radiance), integrated
    over the disc on a fine polar grid about its centre, is the moon lamp's light (colour x
    strength: the moon whole above the horizon) within 1e-4, at any north and exposure; the
    law is lit on the sun's side (its light's centroid towards the sun seen from the moon);
    no moon in the request, no disc."""
    b = place_time.bodies(welkin, dataclass_with(PARIS, hours=hours, north_deg=north))
    assert b.moon_direction[2] > 0.1
    request = sky_request.SkyRequest(
        width=256,
        method="lut",
        exposure=4.0,
        sun_direction=b.sun_direction,
        moon_direction=b.moon_direction,
        moon_irradiance_ratio=b.moon_irradiance_ratio,
        moon_angular_radius_rad=b.moon_angular_radius_rad,
        sun_from_moon=b.sun_from_moon,
    )
    result = sky_compute.compute(welkin, request)
    moon = result.moon_disc
    assert moon is not None
    m, p, alpha = np.array(moon.direction), np.array(moon.sun_from_moon), moon.radius_rad
    # A polar grid about m: rho in [0, alpha), psi around.
    e1 = np.cross(m, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(m, e1)
    nr, npsi = 1000, 2000
    rho = (np.arange(nr) + 0.5) / nr * alpha
    psi = (np.arange(npsi) + 0.5) / npsi * 2.0 * np.pi
    r, q = np.meshgrid(rho, psi, indexing="ij")
    views = (
        np.cos(r)[..., None] * m
        + (np.sin(r) * np.cos(q))[..., None] * e1
        + (np.sin(r) * np.sin(q))[..., None] * e2
    ).reshape(-1, 3)
    law = welkin.moon_disc_relative_radiance(views, m, p, alpha)
    weights = (np.sin(r) * (alpha / nr) * (2.0 * np.pi / npsi)).reshape(-1)
    energy = moon.scale_rgb * float((law * weights).sum())
    atm = sky_request.build_atmosphere(request, welkin)
    lamp = place_time.moon_lamp(
        welkin, atm, 0.0, b.moon_direction, b.moon_irradiance_ratio, b.moon_angular_radius_rad, 4.0
    )
    assert np.allclose(energy, np.asarray(lamp.color) * lamp.strength_w_m2, rtol=1e-4, atol=0.0)
    centroid = (views * (law * weights)[:, None]).sum(axis=0)
    towards = p - np.dot(p, m) * m
    assert np.dot(centroid - np.dot(centroid, m) * m, towards) > 0.0
    assert moon.horizon_z == pytest.approx(sky_compute.horizon_z(atm, 0.0))
    plain = sky_compute.compute(welkin, dataclass_with(request, moon_direction=(), sun_from_moon=()))
    assert plain.moon_disc is None
    assert sky_compute.compute(welkin, request, disc=False).moon_disc is None


def test_moon_disc_names_bad_input():
    atm = welkin.Atmosphere.preset("bruneton2017")
    good = ((0.0, 0.6, 0.8), (0.0, -0.6, 0.8), 0.0045, 2e-6)
    with pytest.raises(ValueError, match="moon_direction"):
        welkin.moon_disc(atm, 0.0, (0.0, 0.0, 0.0), *good[1:])
    with pytest.raises(ValueError, match="irradiance_ratio"):
        welkin.moon_disc(atm, 0.0, *good[:3], 1.0)
    with pytest.raises(ValueError, match="exposure"):
        welkin.moon_disc(atm, 0.0, *good, exposure=0.0)
    with pytest.raises(ValueError, match="views"):
        welkin.moon_disc_relative_radiance(np.zeros((2, 2)), *good[:3])
