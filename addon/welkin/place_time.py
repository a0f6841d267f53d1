# SPDX-License-Identifier: GPL-3.0-or-later
"""Place and Time: the sun and the moon seen from a place at a moment, in the scene's frame.

The Blender layer (blender/sky/place_time.py) fills a PlaceTime from World.welkin_place_time;
`bodies` asks the compiled core (welkin.sun_and_moon: ERFA, apparent topocentric positions,
docs/reference.md "Place and time") where the sun and the moon are, and turns the core's
east-north-up directions into the scene's frame. No astronomy is computed here.

The scene's frame: +Z up, and north along the direction `north_deg` counter-clockwise from
+Y about +Z (0: north is +Y and east +X, the frame of `welkin sky`; 90: north is -X). So a
body at azimuth A (clockwise from north, the astronomers' convention) lies, seen from
above, at the angle north_deg - A counter-clockwise from +Y.

The time is local: the date's midnight plus `hours` (a float, so it can be keyframed; values
beyond [0, 24) carry into the following or previous days, so an animation may cross
midnight), at `utc_offset_h` hours from UTC (2 for central European summer time).
"""

from __future__ import annotations

import dataclasses
import datetime
import math
from typing import TYPE_CHECKING, Any

from . import sky_compute

if TYPE_CHECKING:  # the compiled module's API (native.py)
    from welkin_native_protocol import Module

MAX_ABS_HOURS = 24.0 * 366.0
MAX_ABS_OFFSET_H = 14.0  # the widest offsets in use (UTC-12 to UTC+14)


@dataclasses.dataclass(frozen=True)
class PlaceTime:
    year: int = 2026
    month: int = 6
    day: int = 21
    hours: float = 12.0  # local time since the date's midnight, h
    utc_offset_h: float = 0.0  # local time minus UTC, h (whole minutes)
    latitude_deg: float = 0.0  # north positive
    longitude_deg: float = 0.0  # east positive
    height_m: float = 0.0  # above sea level
    north_deg: float = 0.0  # the scene's north, counter-clockwise from +Y about +Z
    stars: bool = True  # the catalogue's stars in the night sky


@dataclasses.dataclass(frozen=True)
class Bodies:
    """Where the sun and the moon are, in the scene's frame (unit vectors, +Z up)."""

    sun_direction: tuple[float, float, float]
    moon_direction: tuple[float, float, float]
    moon_irradiance_ratio: float  # the moon's irradiance over the sun's at 1 au
    moon_angular_radius_rad: float
    sun_from_moon: tuple[float, float, float]  # lights the moon's disc (its phase)
    place_and_time: dict[str, Any]  # welkin.sun_and_moon's dict, as the core gave it
    # The night sky's moment and place for the world (sky_compute.with_night_sky):
    # (ISO time, latitude_deg, longitude_deg, height_m, north_deg, stars).
    night_sky: tuple[Any, ...] = ()


def iso_time(place_time: PlaceTime) -> str:
    """The moment as ISO 8601 with its UTC offset, to the microsecond. ValueError naming
    the parameter for a date that does not exist, hours or an offset out of range."""
    p = place_time
    try:
        midnight = datetime.datetime(p.year, p.month, p.day)
    except ValueError as error:
        raise ValueError(f"date: {p.year:04d}-{p.month:02d}-{p.day:02d} is not a date ({error})") from None
    if not (math.isfinite(p.hours) and abs(p.hours) <= MAX_ABS_HOURS):
        raise ValueError(f"hours: must be in [{-MAX_ABS_HOURS:g}, {MAX_ABS_HOURS:g}], got {p.hours}")
    if not (math.isfinite(p.utc_offset_h) and abs(p.utc_offset_h) <= MAX_ABS_OFFSET_H):
        raise ValueError(f"utc_offset_h: must be in [-14, 14] h, got {p.utc_offset_h}")
    offset = datetime.timedelta(minutes=round(p.utc_offset_h * 60.0))
    try:
        local = midnight + datetime.timedelta(hours=p.hours)
    except OverflowError:
        raise ValueError(f"hours: {p.hours} h from {midnight.date()} leaves the calendar") from None
    return local.replace(tzinfo=datetime.timezone(offset)).isoformat(timespec="microseconds")


def to_scene(direction_enu: Any, north_deg: float) -> tuple[float, float, float]:  # noqa: ANN401
    """An east-north-up vector in the scene's frame: turned by north_deg about +Z."""
    if not math.isfinite(north_deg):
        raise ValueError(f"north_deg: must be finite, got {north_deg}")
    x, y, z = (float(c) for c in direction_enu)
    c, s = math.cos(math.radians(north_deg)), math.sin(math.radians(north_deg))
    return (c * x - s * y, s * x + c * y, z)


def azimuth_deg(direction: Any, north_deg: float) -> float:  # noqa: ANN401
    """The azimuth, clockwise from the scene's north in [0, 360), of a scene-frame vector:
    the inverse of to_scene's horizontal turn (for checks and the panel)."""
    x, y, _ = to_scene(direction, -north_deg)
    return math.degrees(math.atan2(x, y)) % 360.0


def lamp_euler(direction: Any) -> tuple[float, float, float]:  # noqa: ANN401
    """The XYZ Euler rotation (radians) that turns a lamp's local +Z (towards the light)
    to `direction`: a turn by the zenith angle about X, then by atan2(x, -y) about Z
    (Rz(g) Rx(a) (0, 0, 1) = (sin g sin a, -cos g sin a, cos a))."""
    x, y, z = (float(c) for c in direction)
    n = math.sqrt(x * x + y * y + z * z)
    if not (n > 0.0 and math.isfinite(n)):
        raise ValueError(f"direction: must be a finite non-zero vector, got {(x, y, z)}")
    a = math.acos(max(-1.0, min(1.0, z / n)))
    g = math.atan2(x, -y) if math.hypot(x, y) > 0.0 else 0.0
    return (a, 0.0, g)


def bodies(native: Module, place_time: PlaceTime) -> Bodies:
    """The sun and the moon for `place_time`, from the compiled core. ValueError naming the
    parameter for bad input (the core's own for the place and years outside 1900-2100)."""
    p = place_time
    result = native.sun_and_moon(iso_time(p), p.latitude_deg, p.longitude_deg, p.height_m)
    moon = result["moon"]
    return Bodies(
        to_scene(result["sun"]["direction"], p.north_deg),
        to_scene(moon["direction"], p.north_deg),
        float(moon["irradiance_ratio"]),
        math.radians(float(moon["angular_radius_deg"])),
        to_scene(moon["sun_direction_from_moon"], p.north_deg),
        result,
        (iso_time(p), p.latitude_deg, p.longitude_deg, p.height_m, p.north_deg, bool(p.stars)),
    )


def scene_stars(native: Module, night_sky: tuple[Any, ...]) -> Any:  # noqa: ANN401
    """The catalogue's stars (welkin.stars_at: an (N, 5) array of direction, V, B-V) for a
    Bodies.night_sky, their directions turned into the scene's frame as to_scene turns
    one."""
    time, latitude, longitude, height, north, _stars = night_sky
    stars = native.stars_at(time, latitude, longitude, height_m=height)
    c, s = math.cos(math.radians(north)), math.sin(math.radians(north))
    x, y = stars[:, 0].copy(), stars[:, 1].copy()
    stars[:, 0] = c * x - s * y
    stars[:, 1] = s * x + c * y
    return stars


def moon_lamp(
    native: Module,
    atm: Any,  # noqa: ANN401 (welkin.Atmosphere)
    altitude_m: float,
    moon_direction: Any,  # noqa: ANN401
    irradiance_ratio: float,
    angular_radius_rad: float,
    exposure: float,
) -> sky_compute.LampValues:
    """A moon lamp's values, as the sun lamp's (sky_compute.lamp_values) for a "sun" of the
    moon's size in the moon's direction, times the moon's irradiance ratio: the moon's
    light through the air (`welkin sun --time`'s moon_direct_irradiance_rgb_W_m2; the
    moonlight has the sun's spectrum). `atm` is changed: its sun's radius is the moon's."""
    atm.sun_angular_radius_rad = angular_radius_rad
    lamp = sky_compute.lamp_values(native, atm, altitude_m, moon_direction, exposure * irradiance_ratio)
    return dataclasses.replace(lamp, angle_rad=2.0 * angular_radius_rad)
