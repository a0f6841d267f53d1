# SPDX-License-Identifier: GPL-3.0-or-later
"""Place and Time (World.welkin_place_time): the sun lamp and a moon lamp placed from a date,
a time and a place, by the compiled core (welkin.sun_and_moon; addon/welkin/place_time.py turns its
directions into the scene's frame).

With the mode on, the sky's sun is the core's sun (scene_sun.request_for), the world's sky
adds the moon's light (sky_compute.with_moonlit_sky), the sky's sun lamp is turned towards
the sun, and a second Sun lamp the add-on owns, "Welkin Moon", towards the moon, its
colour, strength and angle synced from the core as the sun lamp's are (Sync Lamp). Every
sky update places them (update.update_sky): the panel's changes (the debounced timer, as
for the other settings) and each frame of an animation (frame_change_post, handlers.py), so
a keyframed Time renders the same in F12, `-a` and on a farm. In a render's own depsgraph
the lamps' evaluated copies are written (what Cycles and EEVEE read) and the values read
from the world's evaluated copy (the animated Time at that frame); see update._sync_lamp
for why the originals are left alone there.
"""

import bpy
from mathutils import Euler, Matrix, Vector

from ... import native, place_time, sky_request
from . import scene_sun  # (which imports this module: names are looked up at call time)

MOON_NAME = "Welkin Moon"
MOON_KEY = "welkin_moon_of"  # on the moon lamp object: the name of the world that owns it


def is_moon_lamp(obj):
    """Whether `obj` is a moon lamp the add-on owns (never the sky's sun lamp)."""
    return obj.get(MOON_KEY) is not None


def _changed(settings, context):
    from .. import handlers

    world = settings.id_data
    if not settings.enabled:
        remove_moon(world)
    handlers.settings_changed(world.welkin, context)


class WelkinPlaceTime(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(
        name="Place and Time",
        default=False,
        update=_changed,
        description="Place the sun lamp and a moon lamp from a date, a time and a place "
        "(apparent positions by the core; the sky adds the moon's light)",
    )
    year: bpy.props.IntProperty(name="Year", default=2026, min=1900, max=2100, update=_changed)
    month: bpy.props.IntProperty(name="Month", default=6, min=1, max=12, update=_changed)
    day: bpy.props.IntProperty(name="Day", default=21, min=1, max=31, update=_changed)
    hours: bpy.props.FloatProperty(
        name="Time (h)",
        default=12.0,
        min=-place_time.MAX_ABS_HOURS,
        max=place_time.MAX_ABS_HOURS,
        soft_min=0.0,
        soft_max=24.0,
        precision=4,
        update=_changed,
        description="Local time of day in hours since the date's midnight (21.5: 21:30); "
        "keyable; beyond 0-24 it carries into the next or previous days",
    )
    utc_offset_h: bpy.props.FloatProperty(
        name="UTC Offset (h)",
        default=0.0,
        min=-14.0,
        max=14.0,
        update=_changed,
        description="Local time minus UTC in hours (2: central European summer time), "
        "rounded to whole minutes",
    )
    latitude_deg: bpy.props.FloatProperty(
        name="Latitude",
        default=48.8566,
        min=-90.0,
        max=90.0,
        precision=4,
        update=_changed,
        description="Geodetic latitude in degrees, north positive",
    )
    longitude_deg: bpy.props.FloatProperty(
        name="Longitude",
        default=2.3522,
        min=-180.0,
        max=180.0,
        precision=4,
        update=_changed,
        description="Longitude in degrees, east positive",
    )
    height_m: bpy.props.FloatProperty(
        name="Height (m)",
        default=0.0,
        min=-500.0,
        max=1e5,
        update=_changed,
        description="The place's height above sea level in metres (refraction, parallax)",
    )
    north_deg: bpy.props.FloatProperty(
        name="North (deg)",
        default=0.0,
        min=-360.0,
        max=360.0,
        update=_changed,
        description="The scene's north: the angle from +Y counter-clockwise about +Z "
        "(0: north is +Y, east +X; 90: north is -X)",
    )
    stars: bpy.props.BoolProperty(
        name="Stars",
        description="The stars of V <= 7 of the Hipparcos catalogue in the world at their places "
        "for the moment, dimmed by the air (the night sky's own glow is always there)",
        default=True,
    )
    moon_object: bpy.props.PointerProperty(type=bpy.types.Object, options={"HIDDEN"})


def _settings(scene, depsgraph):
    world = scene.world
    if world is None:
        return None
    if depsgraph is not None:
        world = world.evaluated_get(depsgraph)  # the animated Time at this frame
    settings = world.welkin_place_time
    return settings if settings.enabled else None


def place_time_of(settings):
    return place_time.PlaceTime(
        settings.year,
        settings.month,
        settings.day,
        settings.hours,
        settings.utc_offset_h,
        settings.latitude_deg,
        settings.longitude_deg,
        settings.height_m,
        settings.north_deg,
        settings.stars,
    )


def bodies_for(scene, depsgraph=None):
    """place_time.Bodies of the scene's world's Place and Time, or None when it is off.
    UserError for bad settings or a missing module."""
    settings = _settings(scene, depsgraph)
    if settings is None:
        return None
    module = native.module()
    if module is None:
        raise scene_sun.UserError(native.message())
    try:
        return place_time.bodies(module, place_time_of(settings))
    except ValueError as error:
        raise scene_sun.UserError(f"Place and Time: {error}") from None


def _aim(obj, direction, depsgraph):
    """Turns `obj` (its evaluated copy in a render's depsgraph) so that its local +Z points
    along `direction`, keeping its location and scale."""
    target = obj
    if depsgraph is not None and depsgraph.mode == "RENDER":
        target = obj.evaluated_get(depsgraph)
    m = target.matrix_world
    if (m.col[2].to_3d().normalized() - Vector(direction)).length < 1e-6:
        return  # already there: no needless depsgraph update
    location, _rotation, scale = m.decompose()
    rotation = Euler(place_time.lamp_euler(direction), "XYZ").to_matrix().to_4x4()
    target.matrix_world = Matrix.Translation(location) @ rotation @ Matrix.Diagonal(scale).to_4x4()


def ensure_moon(scene, world):
    """The world's moon lamp in `scene`, created (and linked to the scene) if missing."""
    settings = world.welkin_place_time
    moon = settings.moon_object
    if moon is None or not is_moon_lamp(moon):
        data = bpy.data.lights.new(MOON_NAME, "SUN")
        moon = bpy.data.objects.new(MOON_NAME, data)
        moon[MOON_KEY] = world.name_full
        settings.moon_object = moon
    if moon.name not in scene.objects:
        scene.collection.objects.link(moon)
    return moon


def remove_moon(world):
    """Deletes the moon lamp the add-on made for `world` (and its light when unused)."""
    if world is None:
        return
    moon = world.welkin_place_time.moon_object
    if moon is None or not is_moon_lamp(moon):
        return
    data = moon.data
    world.welkin_place_time.moon_object = None
    bpy.data.objects.remove(moon)
    if data is not None and data.users == 0:
        bpy.data.lights.remove(data)


def place_lamps(scene, request, sun_lamp, depsgraph=None, sync=None):
    """Turns the sun lamp and the moon lamp to where the core puts the sun and the moon
    (nothing when Place and Time is off), and gives the moon lamp its values through
    sync(lamp, sky_compute.LampValues, depsgraph) (update._sync_lamp; None: Sync Lamp off).
    A render's depsgraph cannot take a new object: a missing moon lamp raises UserError."""
    bodies = bodies_for(scene, depsgraph)
    if bodies is None:
        return
    render = depsgraph is not None and depsgraph.mode == "RENDER"
    moon = scene.world.welkin_place_time.moon_object
    if moon is None or moon.name not in scene.objects:
        world = scene.world
        if world.library is not None or getattr(world, "override_library", None) is not None:
            raise scene_sun.UserError(
                f"Place and Time: world '{world.name}' comes from a "
                f"library: its moon lamp cannot be added here; make the "
                f"world local first; nothing was changed"
            )
        if render:
            raise scene_sun.UserError(
                "Place and Time: the moon lamp is missing; press Update Sky (it adds the lamp), then render"
            )
        moon = ensure_moon(scene, world)
    _aim(sun_lamp, bodies.sun_direction, depsgraph)
    _aim(moon, bodies.moon_direction, depsgraph)
    if sync is not None:
        module = native.module()
        atm = sky_request.build_atmosphere(request, module)
        values = place_time.moon_lamp(
            module,
            atm,
            request.altitude_m,
            bodies.moon_direction,
            bodies.moon_irradiance_ratio,
            bodies.moon_angular_radius_rad,
            request.exposure,
        )
        sync(moon, values, depsgraph)


def place_now(scene):
    """Places the lamps for the current settings without a sky update: before a cloudy sky
    is computed beside the interface (handlers._tick), whose result comes seconds later."""
    from . import update  # (which imports this module)

    settings = scene.world.welkin
    request, lamp, _warnings = scene_sun.request_for(scene, settings, None)
    place_lamps(scene, request, lamp, None, sync=update._sync_lamp if settings.sync_lamp else None)


class WORLD_PT_welkin_place_time(bpy.types.Panel):
    bl_label = "Place and Time"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"
    bl_parent_id = "WORLD_PT_welkin_sky"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        return context.world is not None and not native.message()

    def draw_header(self, context):
        self.layout.prop(context.world.welkin_place_time, "enabled", text="")

    def draw(self, context):
        s = context.world.welkin_place_time
        layout = self.layout
        layout.use_property_split = True
        layout.active = s.enabled
        col = layout.column(align=True)
        col.prop(s, "year")
        col.prop(s, "month")
        col.prop(s, "day")
        col = layout.column()
        col.prop(s, "hours")
        col.prop(s, "utc_offset_h")
        col.separator()
        col.prop(s, "latitude_deg")
        col.prop(s, "longitude_deg")
        col.prop(s, "height_m")
        col.prop(s, "north_deg")
        col.prop(s, "stars")
        # Displaying night: the eye's night vision in the compositor (blender/sky/night_vision.py).
        row = layout.row(align=True)
        row.active = True
        row.operator("welkin.add_night_vision", icon="HIDE_OFF")
        row.operator("welkin.remove_night_vision", icon="X", text="")
        if not s.enabled:
            return
        try:
            bodies = bodies_for(context.scene)
        except scene_sun.UserError as error:
            col.label(text=str(error), icon="ERROR")
            return
        if bodies is None:
            return
        p = bodies.place_and_time
        col.label(text=f"UTC {p['utc']}", icon="TIME")
        col.label(
            text=f"Sun: elevation {p['sun']['elevation_deg']:.2f}, azimuth {p['sun']['azimuth_deg']:.2f}",
            icon="LIGHT_SUN",
        )
        col.label(
            text=f"Moon: elevation {p['moon']['elevation_deg']:.2f}, azimuth "
            f"{p['moon']['azimuth_deg']:.2f}, lit "
            f"{100.0 * p['moon']['illuminated_fraction']:.0f} %",
            icon="LIGHT_SUN",
        )


classes = (WelkinPlaceTime, WORLD_PT_welkin_place_time)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.World.welkin_place_time = bpy.props.PointerProperty(type=WelkinPlaceTime)


def unregister():
    del bpy.types.World.welkin_place_time
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
