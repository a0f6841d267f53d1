# SPDX-License-Identifier: GPL-3.0-or-later
"""The scene side of a sky request: which sun lamp drives it, where it points, and how
high the observer stands."""

import math

from ... import sky_request
from .. import compat
from . import place_time


class UserError(Exception):
    """A problem the user can fix; the message says how. Reported, never a traceback."""


def sun_lamps(scene):
    return sorted(
        (
            o
            for o in scene.objects
            if o.type == "LIGHT" and o.data.type == "SUN" and not place_time.is_moon_lamp(o)
        ),
        key=lambda o: o.name,
    )


def choose_sun(scene, settings):
    """(sun lamp object, warning or None); UserError when there is none."""
    chosen = settings.sun_object if settings is not None else None
    lamps = sun_lamps(scene)
    if chosen is not None and chosen.name in scene.objects:
        return chosen, None
    if not lamps:
        raise UserError(
            "no sun lamp in the scene: add one (Add > Light > Sun) or choose "
            "one in World > Welkin Sky > Sun Lamp"
        )
    warning = None
    if len(lamps) > 1:
        warning = (
            f"{len(lamps)} sun lamps in the scene: the sky follows '{lamps[0].name}' "
            f"(the first by name); choose another in World > Welkin Sky > Sun Lamp"
        )
    return lamps[0], warning


def sun_direction(obj, depsgraph=None):
    """Unit vector towards the sun: the lamp's local +Z in world space (docs/design.md)."""
    if depsgraph is not None:
        obj = obj.evaluated_get(depsgraph)
    z = obj.matrix_world.col[2]
    x, y, zz = float(z[0]), float(z[1]), float(z[2])
    n = math.sqrt(x * x + y * y + zz * zz)
    if not n > 0.0 or not math.isfinite(n):
        raise UserError(
            f"sun lamp '{obj.name}' has a degenerate transform (zero scale): its direction is undefined"
        )
    return (x / n, y / n, zz / n)


def camera_height_m(scene, settings, depsgraph=None):
    camera = scene.camera
    if not settings.use_camera_height or camera is None:
        return 0.0
    if depsgraph is not None:
        camera = camera.evaluated_get(depsgraph)
    return float(camera.matrix_world.translation.z) * scene.unit_settings.scale_length


def request_for(scene, settings, depsgraph=None):
    """(SkyRequest, sun lamp object, warnings). With Place and Time on, the sun's direction
    and the moon are the core's for the world's place and moment (place_time.py)."""
    warnings = []
    bodies = place_time.bodies_for(scene, depsgraph)
    lamp, warning = choose_sun(scene, settings)
    if warning:
        warnings.append(warning)
    altitude, warning = sky_request.observer_altitude(
        settings.altitude_m, camera_height_m(scene, settings, depsgraph)
    )
    if warning:
        warnings.append(warning)
    request = sky_request.SkyRequest(
        preset=settings.preset,
        air_density=settings.air_density,
        aerosol_density=settings.aerosol_density,
        aerosol_optical_depth=(
            settings.aerosol_optical_depth if settings.aerosol_input == "OPTICAL_DEPTH" else -1.0
        ),
        turbidity=settings.turbidity if settings.aerosol_input == "TURBIDITY" else -1.0,
        ozone_density=settings.ozone_density,
        ground_color=() if settings.use_preset_albedo else tuple(float(c) for c in settings.ground_color),
        altitude_m=altitude,
        sun_direction=bodies.sun_direction if bodies else sun_direction(lamp, depsgraph),
        width=int(settings.resolution),
        method=settings.method,
        exposure=settings.exposure,
        ground=settings.show_ground,
        spectral=settings.colour == "SPECTRAL",
        color_space=compat.working_color_space(),
        moon_direction=bodies.moon_direction if bodies else (),
        moon_irradiance_ratio=bodies.moon_irradiance_ratio if bodies else 0.0,
        moon_angular_radius_rad=bodies.moon_angular_radius_rad if bodies else 0.0,
        sun_from_moon=bodies.sun_from_moon if bodies else (),
        night_sky=bodies.night_sky if bodies else (),
    )
    return request, lamp, warnings
