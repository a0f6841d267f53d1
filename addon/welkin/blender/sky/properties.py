# SPDX-License-Identifier: GPL-3.0-or-later
"""World.welkin: the sky's parameters (shown in the panel) and the add-on's state."""

import bpy

from ... import native, sky_request


def _is_sun_lamp(_settings, obj):
    from .place_time import is_moon_lamp

    return obj.type == "LIGHT" and obj.data.type == "SUN" and not is_moon_lamp(obj)


_preset_items = []


def _presets(_self, _context):
    # Blender keeps only the strings of a dynamic enum that Python keeps alive: cache.
    if not _preset_items:
        module = native.module()
        names = module.Atmosphere.preset_names() if module else sky_request.FALLBACK_PRESETS
        _preset_items.extend((n, n, f"Welkin's {n} atmosphere") for n in names)
    return _preset_items


def _changed(settings, context):
    from .. import handlers

    handlers.settings_changed(settings, context)


_METHOD_ITEMS = (
    ("auto", "Auto", "The module's automatic choice where it has one, else lut"),
    ("analytic", "Analytic", "No marching: plane-parallel single scattering (fastest)"),
    ("lut", "LUT", "Hillaire 2020 look-up tables (fast, multiple scattering)"),
    (
        "raymarch",
        "Ray march",
        "Nested single-scattering march plus multiple scattering (tens of seconds at 2048)",
    ),
)


class WelkinWorldSettings(bpy.types.PropertyGroup):
    preset: bpy.props.EnumProperty(
        name="Preset", items=_presets, update=_changed, description="Atmosphere preset"
    )
    air_density: bpy.props.FloatProperty(
        name="Air",
        default=1.0,
        min=0.0,
        max=100.0,
        soft_max=10.0,
        update=_changed,
        description="Multiplier of the preset's Rayleigh (air) scattering",
    )
    aerosol_density: bpy.props.FloatProperty(
        name="Aerosol",
        default=1.0,
        min=0.0,
        max=100.0,
        soft_max=10.0,
        update=_changed,
        description="Multiplier of the preset's aerosol (Mie) scattering and extinction",
    )
    aerosol_input: bpy.props.EnumProperty(
        name="Aerosol Amount",
        update=_changed,
        items=(
            ("PRESET", "Preset", "The preset's aerosol optical depth"),
            ("OPTICAL_DEPTH", "Optical Depth", "The aerosol's vertical optical depth at 550 nm"),
            ("TURBIDITY", "Turbidity", "Preetham's turbidity (2: a clear day, 3: light haze)"),
        ),
        description="How the amount of aerosol (haze) is given; the Aerosol multiplier scales it",
    )
    aerosol_optical_depth: bpy.props.FloatProperty(
        name="Optical Depth (550 nm)",
        default=0.12,
        min=0.0,
        max=10.0,
        soft_max=1.0,
        update=_changed,
        description="Vertical aerosol optical depth at 550 nm: 0.05 very clear, 0.12 an "
        "ordinary clear day, 0.3 hazy, 0.6 polluted",
    )
    turbidity: bpy.props.FloatProperty(
        name="Turbidity",
        default=2.0,
        min=1.0,
        max=20.0,
        soft_max=10.0,
        update=_changed,
        description="Preetham's turbidity T: aerosol optical depth at 550 nm (0.04608 T - 0.04586) 0.55^-1.3",
    )
    ozone_density: bpy.props.FloatProperty(
        name="Ozone",
        default=1.0,
        min=0.0,
        max=100.0,
        soft_max=10.0,
        update=_changed,
        description="Multiplier of the preset's ozone absorption",
    )
    use_preset_albedo: bpy.props.BoolProperty(
        name="Preset Ground Albedo",
        default=True,
        update=_changed,
        description="Use the preset's ground albedo",
    )
    ground_color: bpy.props.FloatVectorProperty(
        name="Ground Colour",
        subtype="COLOR",
        size=3,
        default=(0.1, 0.1, 0.1),
        min=0.0,
        max=1.0,
        update=_changed,
        description="Albedo of the planet's ground as a colour (scene linear), turned into a "
        "smooth reflectance spectrum: the ground below the horizon and the light it sends up",
    )
    altitude_m: bpy.props.FloatProperty(
        name="Origin Altitude (m)",
        default=0.0,
        min=0.0,
        max=1e7,
        soft_max=1e5,
        update=_changed,
        description="Altitude of the scene origin above the ground, metres",
    )
    use_camera_height: bpy.props.BoolProperty(
        name="Add Camera Height",
        default=True,
        update=_changed,
        description="Observer at the scene camera's height above the origin",
    )
    sun_object: bpy.props.PointerProperty(
        name="Sun Lamp",
        type=bpy.types.Object,
        poll=_is_sun_lamp,
        update=_changed,
        description="The sun lamp that drives the sky (empty: the first sun lamp by name)",
    )
    sync_lamp: bpy.props.BoolProperty(
        name="Sync Lamp",
        default=True,
        update=_changed,
        description="Set the lamp's colour, strength (W/m^2) and angle from the sun "
        "transmitted through the atmosphere",
    )
    show_sun_disc: bpy.props.BoolProperty(
        name="Sun Disc for Camera",
        default=True,
        update=_changed,
        description="Show the sun's disc (and, with Place and Time, the moon's) to camera rays "
        "(the lamps do the lighting)",
    )
    show_ground: bpy.props.BoolProperty(
        name="Ground Below Horizon",
        default=True,
        update=_changed,
        description="Show the planet's surface below the horizon, lit by the sun and the "
        "sky with the ground albedo, seen through the air (off: black)",
    )
    exposure: bpy.props.FloatProperty(
        name="Exposure",
        default=1.0,
        min=1e-6,
        max=1e6,
        soft_max=10.0,
        update=_changed,
        description="Multiplies sky, disc and lamp alike (1: physical W m^-2 sr^-1, the "
        "scale of Blender's Nishita sky)",
    )
    resolution: bpy.props.EnumProperty(
        name="Resolution",
        default="1024",
        update=_changed,
        items=[(str(w), f"{w} x {w // 2}", "") for w in sky_request.WIDTHS],
    )
    method: bpy.props.EnumProperty(name="Method", items=_METHOD_ITEMS, default="auto", update=_changed)
    colour: bpy.props.EnumProperty(
        name="Colour",
        default="FAST",
        update=_changed,
        items=(
            (
                "FAST",
                "Fast",
                "Four wavelengths and a conversion fitted to the spectral "
                "path (within 0.005 in CIE xy at the median, twilight included)",
            ),
            (
                "SPECTRAL",
                "Spectral",
                "48 wavelengths, 360 to 830 nm, through the CIE "
                "colour-matching functions: the exact colour, several times slower",
            ),
        ),
        description="How the sky's colour is computed",
    )
    auto_update: bpy.props.BoolProperty(
        name="Follow Lamp",
        default=True,
        description="Update the sky when the sun lamp moves or a setting changes, and on "
        "every frame of animation renders",
    )

    # State kept by the add-on (not shown as parameters).
    active: bpy.props.BoolProperty(default=False, options={"HIDDEN"})
    sky_image: bpy.props.PointerProperty(type=bpy.types.Image, options={"HIDDEN"})
    # The sun-disc image of files saved before the world's nodes drew the disc; the next
    # update removes it (images.drop_disc_image).
    disc_image: bpy.props.PointerProperty(type=bpy.types.Image, options={"HIDDEN"})
    previous_output: bpy.props.StringProperty(options={"HIDDEN"})
    previous_use_nodes: bpy.props.BoolProperty(options={"HIDDEN"})
    previous_sampling: bpy.props.StringProperty(options={"HIDDEN"})  # "METHOD:resolution"
    # World.sun_threshold before the add-on set it (EEVEE Next, 4.2+); -1: not set.
    previous_sun_threshold: bpy.props.FloatProperty(default=-1.0, options={"HIDDEN"})
    last_key: bpy.props.StringProperty(options={"HIDDEN"})
    status: bpy.props.StringProperty(options={"HIDDEN"})
    warnings: bpy.props.StringProperty(options={"HIDDEN"})  # of the last update, one a line
