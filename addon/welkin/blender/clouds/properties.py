# SPDX-License-Identifier: GPL-3.0-or-later
"""World.welkin_clouds (the world's procedural cloud layers and cloud lighting) and
Object.welkin_cloud (a Volume object marked as Welkin clouds).

Defaults and hard ranges are the core's (clouds/procedural.hpp CloudLayerParams,
clouds/lighting.hpp CloudLightingOptions); the soft ranges are what the sliders offer.
"""

import bpy


def _changed(_self, context):
    # A cloud edit changes the sky: the live update follows as for the sky's settings.
    world = getattr(context, "world", None) or getattr(context.scene, "world", None)
    if world is not None:
        from .. import handlers

        handlers.settings_changed(world.welkin, context)


def _type_changed(self, context):
    # A new type loads its preset (the core's welkin.cloud_type_preset) into the layer.
    from ... import native

    try:
        preset = native.module().cloud_type_preset(self.cloud_type)
    except Exception:  # the core not loadable: keep the values, the render reports it
        preset = {}
    for key, value in preset.items():
        if key != "cloud_type" and hasattr(self, key):
            setattr(self, key, value)
    _changed(self, context)


class WelkinCloudLayer(bpy.types.PropertyGroup):
    name: bpy.props.StringProperty(name="Name", default="Cloud Layer")
    enabled: bpy.props.BoolProperty(name="Enabled", default=True, update=_changed)
    bottom_altitude_m: bpy.props.FloatProperty(
        name="Bottom (m)",
        default=1200.0,
        min=0.0,
        max=19999.0,
        soft_max=12000.0,
        update=_changed,
        description="Altitude of the layer's base above the ground, m",
    )
    top_altitude_m: bpy.props.FloatProperty(
        name="Top (m)",
        default=3200.0,
        min=1.0,
        max=20000.0,
        soft_max=15000.0,
        update=_changed,
        description="Altitude of the layer's top above the ground, m (above the bottom)",
    )
    coverage: bpy.props.FloatProperty(
        name="Coverage",
        default=0.4,
        min=0.0,
        max=1.0,
        update=_changed,
        description="Share of the sky a ground observer sees covered (oktas / 8), or of the "
        "ground's area under cloud: see Coverage Measure",
    )
    coverage_measure: bpy.props.EnumProperty(
        name="Coverage Measure",
        default="dome",
        update=_changed,
        items=[
            (
                "dome",
                "Sky Seen Covered (Oktas)",
                "Coverage is the share of the sky dome a ground observer sees covered, the "
                "weather report's cloud amount (oktas / 8): directions above 5 degrees whose "
                "slant optical depth reaches 0.3",
            ),
            (
                "area",
                "Ground Area Under Cloud",
                "Coverage is the share of the ground's area under cloud (a column is cloudy "
                "when its vertical optical depth reaches 0.3); seen from the ground the same "
                "layer covers more of the sky, its clouds' sides filling the gaps",
            ),
        ],
        description="What Coverage measures",
    )
    cloud_type: bpy.props.EnumProperty(
        name="Type",
        default="cumulus",
        update=_type_changed,
        items=[
            ("cumulus", "Cumulus", "Fair-weather heaps with flat bases and towers"),
            ("stratocumulus", "Stratocumulus", "A low lumpy layer of rolls"),
            ("altocumulus", "Altocumulus", "A thin mid-level sheet of small cells"),
            ("stratus", "Stratus", "A low grey sheet that hides the sun"),
            ("cirrus", "Cirrus", "Thin high ice streaks"),
        ],
        description="Cloud type: choosing one sets the layer's values to its preset",
    )
    density_per_m: bpy.props.FloatProperty(
        name="Density (1/m)",
        default=0.04,
        min=0.0,
        max=10.0,
        soft_max=0.2,
        precision=4,
        update=_changed,
        description="Extinction of the densest cloud, m^-1",
    )
    base_scale_m: bpy.props.FloatProperty(
        name="Base Scale (m)",
        default=8000.0,  # the cumulus preset (clouds/procedural.cpp)
        min=10.0,
        max=1e6,
        soft_max=50000.0,
        update=_changed,
        description="Tile size of the base shape noise, m",
    )
    detail_scale_m: bpy.props.FloatProperty(
        name="Detail Scale (m)",
        default=700.0,
        min=1.0,
        max=1e6,
        soft_max=10000.0,
        update=_changed,
        description="Tile size of the erosion noise, m",
    )
    weather_scale_m: bpy.props.FloatProperty(
        name="Weather Scale (m)",
        default=30000.0,
        min=10.0,
        max=1e7,
        soft_max=500000.0,
        update=_changed,
        description="Tile size of the weather map, m",
    )
    detail_strength: bpy.props.FloatProperty(
        name="Detail",
        default=0.5,
        min=0.0,
        max=1.0,
        update=_changed,
        description="How much the detail noise erodes the base shape",
    )
    weather_variation: bpy.props.FloatProperty(
        name="Weather Variation",
        default=0.6,
        min=0.0,
        max=1.0,
        update=_changed,
        description="How much the coverage varies across the weather map",
    )
    wind_offset_m: bpy.props.FloatVectorProperty(
        name="Wind Offset (m)",
        size=2,
        default=(0.0, 0.0),
        min=-1e9,
        max=1e9,
        soft_min=-1e6,
        soft_max=1e6,
        update=_changed,
        description="Horizontal offset of the layer (animate it for wind), m",
    )
    evolution_m: bpy.props.FloatProperty(
        name="Evolution (m)",
        default=0.0,
        min=-1e9,
        max=1e9,
        soft_min=-1e5,
        soft_max=1e5,
        update=_changed,
        description="Moves the cloud noise through the layer's height: animate it and the shapes "
        "change in place while the wind offset carries them, m",
    )
    seed: bpy.props.IntProperty(
        name="Seed", default=1, min=0, update=_changed, description="Seed of the layer's noise"
    )


class WelkinCloudSettings(bpy.types.PropertyGroup):
    layers: bpy.props.CollectionProperty(type=WelkinCloudLayer)
    active_layer: bpy.props.IntProperty(name="Active Layer", default=0, min=0)
    albedo: bpy.props.FloatProperty(
        name="Albedo",
        default=1.0,
        min=0.0,
        max=1.0,
        update=_changed,
        description="Single-scattering albedo of the cloud droplets (1: no absorption)",
    )
    max_steps: bpy.props.IntProperty(
        name="Max Steps",
        default=96,
        min=1,
        max=4096,
        soft_max=512,
        update=_changed,
        description="Samples along each view ray through the clouds",
    )
    light_steps: bpy.props.IntProperty(
        name="Light Steps",
        default=8,
        min=1,
        max=256,
        soft_max=64,
        update=_changed,
        description="Samples along each shadow ray towards the sun",
    )
    ambient_steps: bpy.props.IntProperty(
        name="Ambient Steps",
        default=4,
        min=0,
        max=256,
        soft_max=32,
        update=_changed,
        description="Samples towards the zenith for the sky light's decay (0: none)",
    )
    # The core's default multiple scattering is the delta-Eddington diffusion term, for
    # which only "one order or all" means anything: 1 single scattering, 2 all orders
    # (any count above 1 gives the same image; the count only matters to the core's
    # "octaves" mode, which the panel does not offer).
    octaves: bpy.props.IntProperty(
        name="Scattering Orders",
        default=2,
        min=1,
        max=2,
        update=_changed,
        description="1: single scattering only (faster, darker); 2: all orders of "
        "scattering (the delta-Eddington diffusion term)",
    )
    shadows: bpy.props.BoolProperty(
        name="Shade Sun Lamp",
        default=True,
        update=_changed,
        description="The sun lamp's strength follows the clouds' transmittance towards the "
        "sun at the scene origin (under an overcast it dims, and the cloudy "
        "world's light softens the shadows)",
    )
    lamp_transmittance: bpy.props.FloatProperty(
        default=1.0,
        options={"HIDDEN"},
        description="The clouds' transmittance towards the sun of the last sky update",
    )
    ground_shadows: bpy.props.BoolProperty(
        name="Ground Shadows",
        default=False,
        update=_changed,
        description="The clouds' moving shadows on the scene: a shadow layer (a plane of "
        "the add-on's, seen by shadow rays only) above the scene carries the "
        "clouds' transmittance towards the sun; removed when switched off",
    )
    shadow_extent_m: bpy.props.FloatProperty(
        name="Shadow Extent (m)",
        default=4000.0,
        min=10.0,
        max=1e6,
        soft_max=50000.0,
        update=_changed,
        description="Width of the square shadow layer, centred on the scene origin, m",
    )
    shadow_height_m: bpy.props.FloatProperty(
        name="Shadow Height (m)",
        default=200.0,
        min=0.0,
        max=19999.0,
        soft_max=5000.0,
        update=_changed,
        description="Height of the shadow layer above the scene origin: "
        "above every prop, below the clouds, m",
    )
    shadow_resolution: bpy.props.IntProperty(
        name="Shadow Resolution",
        default=128,
        min=8,
        max=2048,
        soft_max=512,
        update=_changed,
        description="Texels along each side of the shadow map",
    )
    volumes_in_world: bpy.props.BoolProperty(
        name="Volumes in World Sky",
        default=False,
        update=_changed,
        description="Also render the marked VDB volumes into the world's sky texture (for "
        "distant clouds: turn the volume object's camera ray visibility off, or "
        "Cycles and EEVEE show it twice). Off: Cycles and EEVEE render the volume "
        "object themselves and the world holds the cloud layers only; the Welkin "
        "engine and passes always include the volumes",
    )


class WelkinObjectCloud(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(
        name="Welkin Cloud",
        default=False,
        update=_changed,
        description="Render this volume's VDB file as a Welkin cloud (sky, passes, engine)",
    )
    grid: bpy.props.StringProperty(
        name="Grid",
        default="density",
        update=_changed,
        description="Name of the VDB FloatGrid holding the density",
    )
    density_scale: bpy.props.FloatProperty(
        name="Density Scale (1/m)",
        default=1.0,
        min=0.0,
        max=1e6,
        soft_max=100.0,
        precision=4,
        update=_changed,
        description="Extinction per unit grid value, m^-1",
    )


classes = (WelkinCloudLayer, WelkinCloudSettings, WelkinObjectCloud)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.World.welkin_clouds = bpy.props.PointerProperty(type=WelkinCloudSettings)
    bpy.types.Object.welkin_cloud = bpy.props.PointerProperty(type=WelkinObjectCloud)


def unregister():
    del bpy.types.Object.welkin_cloud
    del bpy.types.World.welkin_clouds
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
