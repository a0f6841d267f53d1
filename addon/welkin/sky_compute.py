"""Turning a SkyRequest into the world's images and the sun lamp's values, by calling the
compiled module (never by computing physics here).

Energy appears once (DESIGN.md): the sky image carries no sun disc, because the sun lamp
lights the scene; the disc comes as a second image of its own (welkin.sun_disc_image, the
same energy-exact splat the core adds to HDRIs), which the world shows to camera rays only.

Sun lamp sync (Blender's sun strength is an irradiance in W m^-2; with colour c the lamp
delivers strength x c per channel at normal incidence): the lamp takes the transmitted
direct irradiance of the sun's disc at the observer, welkin.sun(...).direct_irradiance_rgb
(linear Rec.709, W m^-2), times the exposure, as strength = its largest channel and colour =
the irradiance divided by that (so the colour stays within [0, 1]); its angle is the sun's
angular diameter.
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt

from . import sky_request


@dataclasses.dataclass
class LampValues:
    color: tuple[float, ...]  # linear Rec.709, max channel 1
    strength_w_m2: float  # Blender sun strength (irradiance), W m^-2
    angle_rad: float      # angular diameter of the sun's disc


@dataclasses.dataclass
class SkyResult:
    sky: npt.NDArray[np.float32]   # (H, W, 3) float32, top row first, no disc, x exposure
    disc: npt.NDArray[np.float32]  # (H, W, 3) float32, top row first, the disc alone (or zeros)
    lamp: LampValues
    method: str           # the module method that computed it
    sun_elevation_rad: float
    seconds: float
    warnings: list[str]


def lamp_values(native: ModuleType, atm: Any, altitude_m: float,  # noqa: ANN401 (welkin.Atmosphere)
                sun_direction: Sequence[float], exposure: float) -> LampValues:
    sun = native.sun(atm, altitude_m, sun_direction)
    rgb = np.asarray(sun.direct_irradiance_rgb, dtype=np.float64) * exposure
    strength = float(rgb.max()) if rgb.size else 0.0
    color = tuple(float(c) for c in rgb / strength) if strength > 0.0 else (1.0, 1.0, 1.0)
    return LampValues(color, strength, 2.0 * float(atm.sun_angular_radius_rad))


def lamp_for(native: ModuleType, request: sky_request.SkyRequest) -> LampValues:
    """The lamp's values alone for `request` (no images): cheap."""
    sky_request.validate(request, native)
    atm = sky_request.build_atmosphere(request, native)
    return lamp_values(native, atm, request.altitude_m, request.sun_direction, request.exposure)


def sun_elevation_rad(sun_direction: Sequence[float]) -> float:
    x, y, z = (float(c) for c in sun_direction)
    return math.atan2(z, math.hypot(x, y))


def _warnings(atm: Any,  # noqa: ANN401 (welkin.Atmosphere: the compiled module has no stub)
              request: sky_request.SkyRequest) -> tuple[float, list[str]]:
    elevation = sun_elevation_rad(request.sun_direction)
    if elevation < -float(atm.sun_angular_radius_rad):
        return elevation, [f"the sun is {math.degrees(-elevation):.1f} degrees below the horizon: "
                           f"the sun lamp gets strength 0 and the sky shows twilight"]
    return elevation, []


def compute(native: ModuleType, request: sky_request.SkyRequest, *, disc: bool = True,
            scene_json: str | None = None,
            progress: Callable[[float], bool] | None = None) -> SkyResult:
    """SkyResult for `request`; ValueError naming the parameter for bad input.

    `scene_json`: the scene description of the sky with its clouds (its origin at the
    observer, update.cloudy_scene_json); the core then renders the sky with them
    (welkin.scene_sky_image, as `welkin sky --scene`), lit by the same atmosphere, and the
    disc image is dimmed by the clouds' transmittance of its pixels (the factor the core
    dims a disc in the sky image by). `progress`: callable(fraction) -> bool (False
    cancels: KeyboardInterrupt)."""
    start = time.perf_counter()
    sky_request.validate(request, native)
    method = sky_request.resolve_method(request.method, native)
    atm = sky_request.build_atmosphere(request, native)
    elevation, warnings = _warnings(atm, request)
    transmittance = None
    if scene_json is not None:
        sky, transmittance = native.scene_sky_image(
            native.SceneDescription.from_json_string(scene_json), request.width, sun_disc=False,
            return_transmittance=True, progress=progress, ground=request.ground)
    else:
        sky = native.sky_image(atm, request.altitude_m, request.sun_direction, request.width,
                               method, "rgb", sun_disc=False, exposure=request.exposure,
                               ground=request.ground)
    if disc:
        disc_image = native.sun_disc_image(atm, request.altitude_m, request.sun_direction,
                                           request.width, "rgb", exposure=request.exposure)
        if transmittance is not None:
            disc_image *= transmittance[..., None]
    else:
        disc_image = np.zeros_like(sky)
    lamp = lamp_values(native, atm, request.altitude_m, request.sun_direction, request.exposure)
    return SkyResult(sky, disc_image, lamp, method, elevation, time.perf_counter() - start,
                     warnings)


def hdri(native: ModuleType, request: sky_request.SkyRequest, width: int, *,
         sun_disc: bool = True) -> npt.NDArray[np.float32]:
    """(H, W, 3) float32, top row first: the whole sky as an HDRI (with the disc unless
    sun_disc is False), for export."""
    sky_request.validate(dataclasses.replace(request, width=sky_request.WIDTHS[0]), native)
    method = sky_request.resolve_method(request.method, native)
    atm = sky_request.build_atmosphere(request, native)
    return native.sky_image(atm, request.altitude_m, request.sun_direction, width, method,
                            "rgb", sun_disc=sun_disc, exposure=request.exposure,
                            ground=request.ground)
