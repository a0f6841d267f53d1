"""The bpy layer of the add-on: one concern per file, classes registered from one tuple
(in order) and unregistered in reverse.

  properties.py  WelkinWorldSettings (World.welkin): the panel's parameters and the state
                 the add-on keeps (its images, the output node it replaced)
  scene_sun.py   which sun lamp drives the sky, its direction, the observer altitude
  images.py      the world's float images: create, fill, pack
  world_nodes.py the add-on's own nodes in the world tree (the user's stay untouched)
  update.py      one sky update: request -> compute -> images, nodes, lamp
  operators.py   welkin.update_sky, welkin.remove_sky, welkin.export_hdri
  panel.py       Properties > World > Welkin Sky
  aerial.py      aerial perspective per render (Scene.welkin_aerial), compositor.py its nodes
  handlers.py    the sky follows the lamp: depsgraph (debounced timer), frame change, save
  background.py  a cloudy sky for the live UI, computed on a thread beside the interface
  farm.py        a frame the add-on could not prepare fails a command-line render (-a, -f)
  render_engine.py  the render engine "WELKIN": the camera's plate with Welkin's passes
  viewport_preview.py  its viewport preview (Rendered shading), in a background thread
  cloud_properties.py  World.welkin_clouds (layers, lighting), Object.welkin_cloud
  cloud_scene.py     the scene's clouds as the scene JSON's "clouds" section
  cloud_shadows.py   Ground Shadows: the shadow layer (plane, map, material) above the scene
  place_time.py      Place and Time (World.welkin_place_time): sun and moon lamps from a
                     date, a time and a place; its sub-panel
  compat.py          differences between Blender versions
  cloud_operators.py, cloud_panel.py  Welkin Clouds: add/remove layers, mark volumes
"""
import bpy

from . import (aerial, cloud_operators, cloud_panel, cloud_properties, handlers, operators,
               panel, place_time, properties, render_engine)

classes = (
    properties.WelkinWorldSettings,
    operators.WELKIN_OT_update_sky,
    operators.WELKIN_OT_remove_sky,
    operators.WELKIN_OT_export_hdri,
    panel.WORLD_PT_welkin_sky,
    *cloud_operators.classes,
    *cloud_panel.classes,
    render_engine.WelkinRenderEngine,
)


def register():
    cloud_properties.register()
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.World.welkin = bpy.props.PointerProperty(type=properties.WelkinWorldSettings)
    place_time.register()
    handlers.register()
    aerial.register()
    render_engine.register()
    from .. import native
    if native.message():
        print(f"Welkin: {native.message()}")


def unregister():
    render_engine.unregister()
    aerial.unregister()
    handlers.unregister()
    place_time.unregister()
    del bpy.types.World.welkin
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
    cloud_properties.unregister()
