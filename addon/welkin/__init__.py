"""Welkin for Blender: a physically based sky that follows the scene's sun lamp.

The add-on is two layers (as glTF-Blender-IO is):
  * Blender-free modules that plain pytest can test: native.py (finding and loading the
    compiled `welkin` module shipped in _native/), sky_request.py (the plain-data
    description of a sky), sky_compute.py (calling the module: sky image, sun disc, lamp
    radiometry), pixels.py (EXR/top-row-first <-> Blender/bottom-row-first).
  * blender/: properties, operators, panel, handlers, world nodes, images; one concern per
    file, registered from one tuple.
No physics lives here: every number comes from the compiled core.

Nothing at module level imports bpy, so the Blender-free parts import anywhere.
"""

bl_info = {
    "name": "Welkin Sky",
    "author": "Welkin",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > World > Welkin Sky",
    "description": "Physically based sky from the scene's sun lamp: world texture, "
                   "sun lamp sync, HDRI export",
    "category": "Lighting",
}


def register():
    from . import blender
    blender.register()


def unregister():
    from . import blender
    blender.unregister()
