# SPDX-License-Identifier: GPL-3.0-or-later
"""The bpy layer of the add-on, one folder per feature; classes registered from one tuple
(in order) and unregistered in reverse.

  sky/       the world's sky: properties.py (World.welkin: the panel's parameters and the
             add-on's state), scene_sun.py (which sun lamp drives the sky, the observer),
             update.py (one sky update: request -> compute -> images, nodes, lamp),
             images.py, world_nodes.py (the add-on's own nodes; the user's stay untouched),
             operators.py (welkin.update_sky, remove_sky, export_hdri), panel.py,
             background.py (a cloudy sky for the live UI, on a thread beside it),
             place_time.py (World.welkin_place_time: sun and moon lamps from a date, a
             time and a place; its sub-panel), night_vision.py (the compositor group for
             the eye's night vision, welkin.add_night_vision / remove_night_vision)
  clouds/    properties.py (World.welkin_clouds, Object.welkin_cloud), scene.py (the scene
             JSON's "clouds" section), shadows.py (Ground Shadows), operators.py, panel.py
  aerial/    aerial perspective per render (Scene.welkin_aerial): properties.py, panel.py,
             scene.py (on, off, the frame's table and scene JSON), frame.py (in the frame:
             material and compositor groups), pass_files.py and compositor.py (Write Pass
             Files), handlers.py (the handlers; the feature's registration)
  engine/    the render engine "WELKIN" (render_engine.py) and its viewport preview
             (viewport.py)
  handlers.py  the sky follows the lamp: depsgraph (debounced timer), frame change, save
  farm.py      a frame the add-on could not prepare fails a command-line render (-a, -f)
  farm_bake.py Bake for Farm: every frame's images and values for a Blender without Welkin
  compat.py    every difference between Blender versions
"""

import bpy

from . import farm_bake, handlers
from .aerial import handlers as aerial_handlers
from .clouds import operators as cloud_operators
from .clouds import panel as cloud_panel
from .clouds import properties as cloud_properties
from .engine import render_engine
from .sky import night_vision, operators, panel, place_time, properties

classes = (
    properties.WelkinWorldSettings,
    operators.WELKIN_OT_update_sky,
    operators.WELKIN_OT_remove_sky,
    operators.WELKIN_OT_export_hdri,
    panel.WORLD_PT_welkin_sky,
    *night_vision.classes,
    *cloud_operators.classes,
    *cloud_panel.classes,
    render_engine.WelkinRenderEngine,
    *farm_bake.classes,
)


def register():
    cloud_properties.register()
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.World.welkin = bpy.props.PointerProperty(type=properties.WelkinWorldSettings)
    place_time.register()
    handlers.register()
    aerial_handlers.register()
    render_engine.register()
    from .. import native

    if native.message():
        print(f"Welkin: {native.message()}")


def unregister():
    render_engine.unregister()
    aerial_handlers.unregister()
    handlers.unregister()
    place_time.unregister()
    del bpy.types.World.welkin
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
    cloud_properties.unregister()
