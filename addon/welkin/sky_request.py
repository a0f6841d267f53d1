# SPDX-License-Identifier: GPL-3.0-or-later
"""A sky request: everything that decides the world image, as plain data.

The Blender layer fills a SkyRequest from the world's Welkin settings and the scene (the
sun lamp's direction, the camera height); sky_compute turns it into images and lamp
values. Two requests that compare equal give the same sky, so `key()` tells the handlers
whether the world image is already up to date.

Atmosphere parameters are the preset's, with three density multipliers in the spirit of
Blender's Nishita sky (air, dust, ozone): they scale the preset's Rayleigh scattering, its
aerosol (Mie) scattering and extinction, and its ozone absorption. The aerosol can instead
be given as its optical depth at 550 nm, or as Preetham's turbidity (the core converts
it); the aerosol multiplier then scales that. Scaling a coefficient is not new physics:
the core still computes every number.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the compiled module's API (native.py)
    import welkin_native
    from welkin_native_protocol import Module

FALLBACK_PRESETS = (
    "clear_day",
    "clear",
    "hazy",
    "polluted",
    "desert_dust",
    "maritime",
    "mars",
    "bruneton2017",
)
# Methods the add-on offers. "reference" (Monte-Carlo, hours at 2048 wide) is left to the
# CLI and the module: a live sky must not freeze Blender.
LIVE_METHODS = ("auto", "analytic", "lut", "raymarch")
WIDTHS = (256, 512, 1024, 2048, 4096)


# The linear RGB spaces the core writes (include/welkin/color/color_space.hpp).
COLOR_SPACES = ("rec709", "rec2020", "acescg")


@dataclasses.dataclass(frozen=True)
class SkyRequest:
    preset: str = "clear_day"
    air_density: float = 1.0  # x Rayleigh scattering
    aerosol_density: float = 1.0  # x Mie scattering and extinction
    aerosol_optical_depth: float = -1.0  # at 550 nm, in [0, 10]; < 0: the preset's
    turbidity: float = -1.0  # Preetham's T in [1, 20], instead; < 0: not used
    ozone_density: float = 1.0  # x ozone absorption
    ground_albedo: float = -1.0  # grey, in [0, 1]; < 0: the preset's
    # The ground's colour, linear RGB of color_space in [0, 1], as a reflectance spectrum
    # (the core's rgb_to_reflectance, Jakob & Hanika 2019); (): ground_albedo or the preset's.
    ground_color: tuple[float, ...] = ()
    altitude_m: float = 0.0  # observer above the ground, m (>= 0)
    sun_direction: tuple[float, ...] = (0.0, 0.0, 1.0)  # towards the sun, Z up
    width: int = 1024  # equirect width; height = width / 2
    method: str = "auto"
    exposure: float = 1.0
    ground: bool = True  # the lit ground below the horizon (False: black)
    spectral: bool = False  # 48 wavelengths (exact colour) instead of the default 4
    color_space: str = "rec709"  # linear RGB of every colour: rec709, rec2020, acescg
    # The moon's light (Place and Time, place_time.py): the sky adds the same method's sky
    # for a "sun" in the moon's direction times the moon's irradiance ratio; (): no moon.
    moon_direction: tuple[float, ...] = ()
    moon_irradiance_ratio: float = 0.0
    # The moon's disc (the HDRI export draws it): its radius and the sun's direction from it.
    moon_angular_radius_rad: float = 0.0
    sun_from_moon: tuple[float, ...] = ()
    # The night sky (Place and Time): (ISO time, latitude, longitude, height, north_deg,
    # stars) as place_time.Bodies.night_sky; (): none. The world adds the night sky's own
    # glow and, with stars, the catalogue's stars (sky_compute.with_night_sky).
    night_sky: tuple[Any, ...] = ()

    def key(self) -> str:
        """A string that changes whenever the sky would (sun rounded to 1e-7)."""
        d = dataclasses.asdict(self)
        d["sun_direction"] = tuple(round(float(c), 7) for c in self.sun_direction)
        d["moon_direction"] = tuple(round(float(c), 7) for c in self.moon_direction)
        d["sun_from_moon"] = tuple(round(float(c), 7) for c in self.sun_from_moon)
        d["ground_color"] = tuple(float(c) for c in self.ground_color)
        return repr(sorted(d.items()))


def validate(request: SkyRequest, native: Module) -> None:
    """Raises ValueError naming the parameter and its accepted range."""
    names = native.Atmosphere.preset_names()
    if request.preset not in names:
        raise ValueError(f"preset: must be one of {', '.join(names)}, got {request.preset!r}")
    for name in ("air_density", "aerosol_density", "ozone_density"):
        value = getattr(request, name)
        if not (math.isfinite(value) and 0.0 <= value <= 100.0):
            raise ValueError(f"{name}: must be in [0, 100], got {value}")
    aod, turbidity = request.aerosol_optical_depth, request.turbidity
    if not (math.isfinite(aod) and aod <= 10.0):
        raise ValueError(f"aerosol_optical_depth: must be in [0, 10] (or < 0 for the preset's), got {aod}")
    if not (math.isfinite(turbidity) and (turbidity < 0.0 or 1.0 <= turbidity <= 20.0)):
        raise ValueError(f"turbidity: must be in [1, 20] (or < 0: not used), got {turbidity}")
    if not (request.ground_albedo < 0.0 or request.ground_albedo <= 1.0):
        raise ValueError(
            f"ground_albedo: must be in [0, 1] (or < 0 for the preset's), got {request.ground_albedo}"
        )
    g = request.ground_color
    if g and (len(g) != 3 or not all(math.isfinite(c) and 0.0 <= c <= 1.0 for c in g)):
        raise ValueError(f"ground_color: must be 3 channels each in [0, 1], got {tuple(g)}")
    if not (math.isfinite(request.altitude_m) and request.altitude_m >= 0.0):
        raise ValueError(f"altitude_m: must be >= 0 m, got {request.altitude_m}")
    if request.width not in WIDTHS:
        raise ValueError(f"width: must be one of {', '.join(map(str, WIDTHS))}, got {request.width}")
    if request.color_space not in COLOR_SPACES:
        raise ValueError(
            f"color_space: must be one of {', '.join(COLOR_SPACES)}, got {request.color_space!r}"
        )
    if not (math.isfinite(request.exposure) and 0.0 < request.exposure <= 1e6):
        raise ValueError(f"exposure: must be in (0, 1e6], got {request.exposure}")
    s = request.sun_direction
    if len(s) != 3 or not all(math.isfinite(c) for c in s) or math.hypot(*s) == 0.0:
        raise ValueError(f"sun_direction: must be a finite non-zero vector, got {tuple(s)}")
    m = request.moon_direction
    if m and (len(m) != 3 or not all(math.isfinite(c) for c in m) or math.hypot(*m) == 0.0):
        raise ValueError(f"moon_direction: must be a finite non-zero vector, got {tuple(m)}")
    if not (math.isfinite(request.moon_irradiance_ratio) and 0.0 <= request.moon_irradiance_ratio <= 1e-3):
        raise ValueError(f"moon_irradiance_ratio: must be in [0, 1e-3], got {request.moon_irradiance_ratio}")
    resolve_method(request.method, native)


def resolve_method(method: str, native: Module) -> str:
    """The module's method for `method`: "auto" is the module's own automatic choice
    where it has one, else "lut" (Hillaire 2020, the fast default)."""
    available = list(native.methods())
    if method == "auto":
        return "auto" if "auto" in available else "lut"
    if method not in available or method not in LIVE_METHODS:
        offered = [m for m in LIVE_METHODS if m == "auto" or m in available]
        raise ValueError(f"method: must be one of {', '.join(offered)}, got {method!r}")
    return method


def build_atmosphere(request: SkyRequest, native: Module) -> welkin_native.Atmosphere:
    """The preset with the request's aerosol optical depth (or turbidity) and multipliers
    applied (validated by the core), at the
    default four wavelengths or, `spectral`, at 360..830 nm every 10 nm (48; the colour the
    default's fitted conversion approximates, at several times the cost)."""
    atm = (
        native.Atmosphere.preset(request.preset, native.spectral_wavelengths_nm())
        if request.spectral
        else native.Atmosphere.preset(request.preset)
    )
    if request.turbidity >= 0.0:
        atm.set_aerosol_optical_depth(native.preetham_turbidity_to_aerosol_optical_depth(request.turbidity))
    elif request.aerosol_optical_depth >= 0.0:
        atm.set_aerosol_optical_depth(request.aerosol_optical_depth)
    if request.air_density != 1.0:
        atm.rayleigh_scattering = atm.rayleigh_scattering * request.air_density
    if request.aerosol_density != 1.0:
        atm.mie_scattering = atm.mie_scattering * request.aerosol_density
        atm.mie_extinction = atm.mie_extinction * request.aerosol_density
    if request.ozone_density != 1.0:
        atm.absorption_extinction = atm.absorption_extinction * request.ozone_density
    if request.ground_color:
        atm.ground_albedo = native.rgb_to_reflectance(
            request.ground_color, atm.wavelengths_nm, color_space=request.color_space
        )
    elif request.ground_albedo >= 0.0:
        atm.ground_albedo = [request.ground_albedo] * len(atm.wavelengths_nm)
    atm.validate()
    return atm


def observer_altitude(origin_altitude_m: float, camera_z_m: float) -> tuple[float, str | None]:
    """Altitude of the observer (the camera) above the ground: the scene origin's altitude
    plus the camera's height in the scene (Z up, metres). Returns (altitude_m, warning or
    None); an observer below the ground is put on it, with a warning."""
    altitude = float(origin_altitude_m) + float(camera_z_m)
    if altitude < 0.0:
        return 0.0, (
            f"the camera is {-altitude:.3g} m below the ground (origin altitude "
            f"{origin_altitude_m:.6g} m + camera height {camera_z_m:.6g} m): the sky "
            f"is computed for an observer on the ground (0 m)"
        )
    return altitude, None
