# SPDX-License-Identifier: GPL-3.0-or-later
"""Turning a SkyRequest into the world's images and the sun lamp's values, by calling the
compiled module (never by computing physics here).

Energy appears once (docs/design.md): the sky image carries no sun disc, because the sun lamp
lights the scene; the world draws the disc with shader nodes from the view direction
(world_nodes.py), shown to camera rays only, from the numbers of a DiscModel: the disc's
centre, angular radius and horizon, and its radiance profile as a polynomial in mu (below).
The exported HDRI keeps the core's own energy-exact disc (welkin.sky_image). The moon
(Place and Time) is done alike: its lamp lights the scene, and the world draws its disc with
its phase for camera rays only, from a MoonDiscModel (welkin.moon_disc).

Sun lamp sync (Blender's sun strength is an irradiance in W m^-2; with colour c the lamp
delivers strength x c per channel at normal incidence): the lamp takes the transmitted
direct irradiance of the sun's disc at the observer, welkin.sun(...).direct_irradiance_rgb
(linear RGB of the request's colour space, W m^-2), times the exposure, as strength = its largest channel and colour =
the irradiance divided by that (so the colour stays within [0, 1]); its angle is the sun's
angular diameter.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from . import place_time, sky_request

if TYPE_CHECKING:  # the compiled module's API (native.py)
    from welkin_native_protocol import Module


@dataclasses.dataclass
class LampValues:
    color: tuple[float, ...]  # linear RGB of the request's colour space, max channel 1
    strength_w_m2: float  # Blender sun strength (irradiance), W m^-2
    angle_rad: float  # angular diameter of the sun's disc


@dataclasses.dataclass
class DiscModel:
    """The sun's disc as the world's nodes draw it. A view direction at angle rho from
    `direction` sees, when rho < radius_rad and its z is above horizon_z, the radiance
        L_c(rho) = sum_k coefficients[k, c] mu^k,   mu = sqrt(1 - (sin rho / sin radius)^2)
    (mu: the cosine of the heliocentric angle, sun.hpp), linear RGB (the request's colour
    space) W m^-2 sr^-1 times
    the exposure; its integral over the visible disc is the lamp's direct irradiance."""

    direction: tuple[float, float, float]  # unit vector towards the disc's centre
    radius_rad: float  # angular radius of the disc
    horizon_z: float  # z of the horizon's direction (0 on the ground)
    coefficients: npt.NDArray[np.float64]  # (DEGREE + 1, 3)

    DEGREE = 5


@dataclasses.dataclass
class MoonDiscModel:
    """The moon's disc as the world's nodes draw it (welkin.moon_disc; its phase from the
    sun's direction seen from the moon). A view direction v above horizon_z sees
        L_c = scale_rgb[c] x f(v),   f = mu0 / (mu0 + mu) where mu0 > 0 and s < 1, else 0,
        s = |v x m| / sin(radius), mu = sqrt(1 - s^2),
        mu0 = (v x m) . (sun_from_moon x m) / sin(radius) - mu (m . sun_from_moon)
    (Lommel-Seeliger seen from afar: welkin.moon_disc_relative_radiance), linear RGB (the
    request's colour space) W m^-2 sr^-1 times the exposure; its integral over the disc is
    the moon's irradiance through the air, the moon lamp's light over its visible fraction."""

    direction: tuple[float, float, float]  # unit vector m towards the disc's centre
    sun_from_moon: tuple[float, float, float]  # unit vector from the moon towards the sun
    radius_rad: float  # angular radius of the disc
    horizon_z: float  # z of the horizon's direction (0 on the ground)
    scale_rgb: npt.NDArray[np.float64]  # (3,)


@dataclasses.dataclass
class SkyResult:
    sky: npt.NDArray[np.float32]  # (H, W, 3) float32, top row first, no disc, x exposure
    disc: DiscModel | None  # None: no disc shown (or the sun below the horizon)
    lamp: LampValues
    method: str  # the module method that computed it
    sun_elevation_rad: float
    seconds: float
    warnings: list[str]
    lamp_transmittance: float = 1.0  # the clouds' towards the sun at the scene origin
    shadow_map: npt.NDArray[np.float32] | None = None  # (n, n) T, rows bottom first
    moon_disc: MoonDiscModel | None = None  # None: no moon, or none of its disc shown


def lamp_values(
    native: Module,
    atm: Any,  # noqa: ANN401 (welkin.Atmosphere)
    altitude_m: float,
    sun_direction: Sequence[float],
    exposure: float,
    color_space: str = "rec709",
) -> LampValues:
    sun = native.sun(atm, altitude_m, sun_direction, color_space=color_space)
    rgb = np.asarray(sun.direct_irradiance_rgb, dtype=np.float64) * exposure
    strength = float(rgb.max()) if rgb.size else 0.0
    color = tuple(float(c) for c in rgb / strength) if strength > 0.0 else (1.0, 1.0, 1.0)
    return LampValues(color, strength, 2.0 * float(atm.sun_angular_radius_rad))


def horizon_z(atm: Any, altitude_m: float) -> float:  # noqa: ANN401 (welkin.Atmosphere)
    """z of the direction of the horizon of a spherical ground of radius R seen from
    r = R + altitude (the tangent ray): sin(elevation) = -sqrt(r^2 - R^2) / r."""
    radius = float(atm.bottom_radius_m)
    r = radius + altitude_m
    return -math.sqrt(max(0.0, (r - radius) * (r + radius))) / r


def disc_model(
    native: Module,
    atm: Any,  # noqa: ANN401
    altitude_m: float,
    sun_direction: Sequence[float],
    exposure: float,
    color_space: str = "rec709",
) -> DiscModel | None:
    """The disc for the world's nodes, or None when none of it is above the horizon."""
    x, y, z = (float(c) for c in sun_direction)
    norm = math.sqrt(x * x + y * y + z * z)
    direction = (x / norm, y / norm, z / norm)
    sun = native.sun(atm, altitude_m, direction, color_space=color_space)
    if not float(sun.visible_fraction) > 0.0:
        return None
    alpha = float(sun.angular_radius_rad)
    # The core's disc (sun_disc.hpp): L_j(mu) = centre_radiance_rgb[j] sum_k b[j, k] mu^k,
    # limb-darkened by Neckel & Labs 1994, its integral over the visible disc the direct
    # irradiance.
    centre = np.asarray(sun.centre_radiance_rgb, dtype=np.float64) * exposure
    coefficients = (np.asarray(sun.limb_coefficients_rgb, dtype=np.float64) * centre[:, None]).T.copy()
    return DiscModel(direction, alpha, horizon_z(atm, altitude_m), coefficients)


def _unit(v: Sequence[float]) -> tuple[float, float, float]:
    x, y, z = (float(c) for c in v)
    n = math.sqrt(x * x + y * y + z * z)
    return (x / n, y / n, z / n)


def moon_disc_model(
    native: Module,
    atm: Any,  # noqa: ANN401 (welkin.Atmosphere)
    request: sky_request.SkyRequest,
) -> MoonDiscModel | None:
    """The moon's disc for the world's nodes (Place and Time), or None: no moon in the
    request, a new moon, or the disc wholly below the horizon."""
    if not (request.moon_direction and request.sun_from_moon and request.moon_irradiance_ratio > 0.0):
        return None
    m, s = _unit(request.moon_direction), _unit(request.sun_from_moon)
    radius = float(request.moon_angular_radius_rad)
    horizon = horizon_z(atm, request.altitude_m)
    if math.asin(max(-1.0, min(1.0, m[2]))) + radius < math.asin(horizon):
        return None
    disc = native.moon_disc(
        atm,
        request.altitude_m,
        m,
        s,
        radius,
        request.moon_irradiance_ratio,
        exposure=request.exposure,
        color_space=request.color_space,
    )
    scale = np.asarray(disc["radiance_scale_rgb"], dtype=np.float64)
    if not float(disc["relative_integral_sr"]) > 0.0 or not np.any(scale > 0.0):
        return None
    return MoonDiscModel(m, s, radius, horizon, scale.copy())


def shaded_lamp(lamp: LampValues, transmittance: float) -> LampValues:
    """The lamp under clouds of transmittance T towards the sun (Beer-Lambert along the
    direct beam, clouds/shadow.hpp): its strength times T. Cloud droplets' extinction is
    grey (Mie, droplets ~10 um, density.hpp), so the beam's colour is the clear sun's; the
    light the clouds scatter instead reaches the scene from the world's cloudy sky, which
    is what softens the shadows under an overcast."""
    t = min(max(float(transmittance), 0.0), 1.0)
    return dataclasses.replace(lamp, strength_w_m2=lamp.strength_w_m2 * t)


def lamp_transmittance(
    native: Module, shadow_json: str, progress: Callable[[float], bool] | None = None
) -> float:
    """The clouds' transmittance towards the sun at the origin of `shadow_json` (a scene
    description whose origin is the scene's: update.shadow_scene_json)."""
    t = native.cloud_transmittance(
        native.SceneDescription.from_json_string(shadow_json), np.zeros((1, 3)), progress=progress
    )
    return float(t[0])


def lamp_for(native: Module, request: sky_request.SkyRequest) -> LampValues:
    """The lamp's values alone for `request` (no images): cheap."""
    sky_request.validate(request, native)
    atm = sky_request.build_atmosphere(request, native)
    return lamp_values(
        native, atm, request.altitude_m, request.sun_direction, request.exposure, request.color_space
    )


def sun_elevation_rad(sun_direction: Sequence[float]) -> float:
    x, y, z = (float(c) for c in sun_direction)
    return math.atan2(z, math.hypot(x, y))


def _warnings(
    atm: Any,  # noqa: ANN401 (welkin.Atmosphere: the compiled module has no stub)
    request: sky_request.SkyRequest,
) -> tuple[float, list[str]]:
    elevation = sun_elevation_rad(request.sun_direction)
    if elevation < -float(atm.sun_angular_radius_rad):
        return elevation, [
            f"the sun is {math.degrees(-elevation):.1f} degrees below the horizon: "
            f"the sun lamp gets strength 0 and the sky shows twilight"
        ]
    return elevation, []


def compute(
    native: Module,
    request: sky_request.SkyRequest,
    *,
    disc: bool = True,
    scene_json: str | None = None,
    shadow_json: str | None = None,
    shade_lamp: bool = True,
    shadow_map: Callable[[str], npt.NDArray[np.float32]] | None = None,
    progress: Callable[[float], bool] | None = None,
) -> SkyResult:
    """SkyResult for `request`; ValueError naming the parameter for bad input.

    `scene_json`: the scene description of the sky with its clouds (its origin at the
    observer, update.cloudy_scene_json); the core then renders the sky with them
    (welkin.scene_sky_image, as `welkin sky --scene`), lit by the same atmosphere, and the
    disc is dimmed by the clouds' transmittance towards the sun's centre (the core dims an
    HDRI's disc pixel by pixel). With Place and Time the moon lights the clouds too, and
    the moonlit sky, the night glow and the stars shine through them (night_under_clouds).
    `shadow_json`: the clouds that shade the sun lamp,
    in a scene description centred on the scene origin (update.shadow_scene_json): the
    lamp's strength is then times their transmittance towards the sun there (shaded_lamp),
    unless shade_lamp is False; `shadow_map`: callable(shadow_json) -> the ground shadows'
    map (cloud_shadows.shadow_map), kept in the result.
    `progress`: callable(fraction) -> bool (False cancels: KeyboardInterrupt)."""
    start = time.perf_counter()
    sky_request.validate(request, native)
    method = sky_request.resolve_method(request.method, native)
    atm = sky_request.build_atmosphere(request, native)
    elevation, warnings = _warnings(atm, request)
    transmittance = None
    if scene_json is not None:
        sky, transmittance = native.scene_sky_image(
            native.SceneDescription.from_json_string(scene_json),
            request.width,
            sun_disc=False,
            return_transmittance=True,
            progress=progress,
            ground=request.ground,
            **night_under_clouds(native, request),
        )
    else:
        sky = native.sky_image(
            atm,
            request.altitude_m,
            request.sun_direction,
            request.width,
            method,
            "rgb",
            sun_disc=False,
            exposure=request.exposure,
            ground=request.ground,
            color_space=request.color_space,
        )
        sky = with_moonlit_sky(native, request, atm, method, sky, request.color_space)
        sky = with_night_sky(native, request, atm, sky, request.color_space)
    model = None
    if disc:
        model = disc_model(
            native, atm, request.altitude_m, request.sun_direction, request.exposure, request.color_space
        )
        if model is not None and transmittance is not None:
            model.coefficients *= _pixel_at(native, transmittance, model.direction)
    moon = moon_disc_model(native, atm, request) if disc else None
    if moon is not None and transmittance is not None:
        moon.scale_rgb *= _pixel_at(native, transmittance, moon.direction)
    lamp = lamp_values(
        native, atm, request.altitude_m, request.sun_direction, request.exposure, request.color_space
    )
    shade, ground = 1.0, None
    if shadow_json is not None and shade_lamp:
        shade = lamp_transmittance(native, shadow_json)
        lamp = shaded_lamp(lamp, shade)
    if shadow_json is not None and shadow_map is not None:
        ground = shadow_map(shadow_json)
    return SkyResult(
        sky, model, lamp, method, elevation, time.perf_counter() - start, warnings, shade, ground, moon
    )


def _pixel_at(native: Module, image: npt.NDArray[np.float32], direction: Sequence[float]) -> float:
    """The value of an (H, W) top-row-first equirectangular image at `direction`."""
    h, w = image.shape[:2]
    u, v = native.direction_to_equirect(np.asarray(direction, dtype=np.float64))
    return float(image[min(h - 1, int((1.0 - v) * h)), min(w - 1, int(u * w) % w)])


def hdri(
    native: Module,
    request: sky_request.SkyRequest,
    width: int,
    *,
    sun_disc: bool = True,
    scene_json: str | None = None,
    progress: Callable[[float], bool] | None = None,
) -> npt.NDArray[np.float32]:
    """(H, W, 3) float32, top row first: the whole sky as an HDRI (with the disc unless
    sun_disc is False), for export. `scene_json`: the cloudy sky's scene description (as
    for compute): the HDRI is then the world's cloudy sky, the clouds composited over it
    and the disc dimmed by their transmittance (welkin.scene_sky_image), the sky the world
    shows; `progress` as for compute. A request with a moon (Place and Time) adds the
    moonlit sky (and its light on the clouds), the night sky and, with sun_disc, the
    moon's disc: the image welkin.sky_image_at renders for that moment, in the scene's
    frame. In linear Rec.709
    whatever the request's colour space: an EXR carries no colour space, and Rec.709 is
    what HDRIs are read as."""
    sky_request.validate(dataclasses.replace(request, width=sky_request.WIDTHS[0]), native)
    if scene_json is not None:
        scene = json.loads(scene_json)
        scene["color_space"] = "rec709"
        image: npt.NDArray[np.float32] = native.scene_sky_image(
            native.SceneDescription.from_json_string(json.dumps(scene)),
            width,
            sun_disc=sun_disc,
            progress=progress,
            **night_under_clouds(native, request),
        )
        return image
    method = sky_request.resolve_method(request.method, native)
    atm = sky_request.build_atmosphere(request, native)
    sky = native.sky_image(
        atm,
        request.altitude_m,
        request.sun_direction,
        width,
        method,
        "rgb",
        sun_disc=sun_disc,
        exposure=request.exposure,
        ground=request.ground,
    )
    sky = with_moonlit_sky(native, dataclasses.replace(request, width=width), atm, method, sky, "rec709")
    sky = with_night_sky(native, dataclasses.replace(request, width=width), atm, sky, "rec709")
    if sun_disc and request.moon_direction and request.sun_from_moon:
        # The moon's disc with its phase, energy-exact, as welkin.sky_image_at draws it.
        sky = sky + native.moon_disc_image(
            atm,
            request.altitude_m,
            request.moon_direction,
            request.sun_from_moon,
            request.moon_angular_radius_rad,
            request.moon_irradiance_ratio,
            width,
            exposure=request.exposure,
        )
    return sky


MOON_SKY_DEPRESSION_DEG = 20.0  # the core's kMoonSkyDepressionDeg


def _moment_kwargs(night_sky: tuple[Any, ...]) -> dict[str, Any]:
    """The moment and place of a request's night sky as the keyword arguments of
    welkin.night_glow_image and scene_sky_image (time, latitude_deg, longitude_deg,
    height_m, north_deg)."""
    time, latitude, longitude, height, north, _stars = night_sky
    return {
        "time": time,
        "latitude_deg": latitude,
        "longitude_deg": longitude,
        "height_m": height,
        "north_deg": north,
    }


def night_under_clouds(native: Module, request: sky_request.SkyRequest) -> dict[str, Any]:
    """welkin.scene_sky_image's keyword arguments for the night sky of a request with a
    moon or a night sky (Place and Time), in the scene's frame: the moon (its sky, its
    light on the clouds, its disc where the image has discs), the night glow and, with
    stars, the catalogue's stars; the core composes them under the clouds, each dimmed by
    the clouds' transmittance towards it. Empty without Place and Time."""
    kwargs: dict[str, Any] = {}
    if request.moon_direction and request.sun_from_moon and request.moon_irradiance_ratio > 0.0:
        kwargs["moon_direction"] = tuple(request.moon_direction)
        kwargs["sun_from_moon"] = tuple(request.sun_from_moon)
        kwargs["moon_angular_radius_rad"] = request.moon_angular_radius_rad
        kwargs["moon_irradiance_ratio"] = request.moon_irradiance_ratio
    if request.night_sky:
        kwargs.update(night_glow=True, **_moment_kwargs(request.night_sky))
        if request.night_sky[5]:
            kwargs["stars"] = place_time.scene_stars(native, request.night_sky)
    return kwargs


def with_night_sky(
    native: Module,
    request: sky_request.SkyRequest,
    atm: Any,  # noqa: ANN401 (welkin.Atmosphere)
    sky: npt.NDArray[np.float32],
    color_space: str,
) -> npt.NDArray[np.float32]:
    """`sky` plus the night sky when the request has one (Place and Time), as
    welkin.sky_image_at adds it: the night sky's own glow (welkin.night_glow_image: the
    airglow and the zodiacal light along the moment's ecliptic) and, with stars, the
    catalogue's stars, both in the scene's frame (welkin.star_image, energy-exact).
    Under clouds the core adds it instead (night_under_clouds)."""
    if not request.night_sky:
        return sky
    altitude_m, exposure = request.altitude_m, request.exposure
    sky = sky + native.night_glow_image(
        atm,
        request.width,
        altitude_m=altitude_m,
        exposure=exposure,
        color_space=color_space,
        **_moment_kwargs(request.night_sky),
    )
    if request.night_sky[5]:
        stars = place_time.scene_stars(native, request.night_sky)
        sky = sky + native.star_image(
            atm, stars, request.width, altitude_m=altitude_m, exposure=exposure, color_space=color_space
        )
    return sky


def with_moonlit_sky(
    native: Module,
    request: sky_request.SkyRequest,
    atm: Any,  # noqa: ANN401 (welkin.Atmosphere)
    method: str,
    sky: npt.NDArray[np.float32],
    color_space: str,
) -> npt.NDArray[np.float32]:
    """`sky` plus the moon's sky when the request has a moon (Place and Time): the same
    method's sky, in `color_space`, for a "sun" in the moon's direction times the moon's
    irradiance ratio, as the core composes it (night/moonlit_sky.cpp: every method's
    radiance is linear in the solar irradiance). The moon's disc is not in it (the world's
    nodes draw it: MoonDiscModel; hdri adds the core's)."""
    if not request.moon_direction or not request.moon_irradiance_ratio > 0.0:
        return sky
    # Far below the horizon the moon's sky is negligible and left out, as the core does
    # (kMoonSkyDepressionDeg, include/welkin/night/moonlit_sky.hpp).
    m = request.moon_direction
    if m[2] / math.sqrt(m[0] ** 2 + m[1] ** 2 + m[2] ** 2) < math.sin(math.radians(-MOON_SKY_DEPRESSION_DEG)):
        return sky
    moonlit = native.sky_image(
        atm,
        request.altitude_m,
        request.moon_direction,
        request.width,
        method,
        "rgb",
        sun_disc=False,
        exposure=request.exposure,
        ground=request.ground,
        color_space=color_space,
    )
    return sky + np.float32(request.moon_irradiance_ratio) * moonlit
