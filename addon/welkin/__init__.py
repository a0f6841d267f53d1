# SPDX-License-Identifier: GPL-3.0-or-later
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


MINIMUM_BLENDER = (3, 4, 0)
_registered = False


def register():
    global _registered
    import bpy

    if bpy.app.version < MINIMUM_BLENDER:
        print(
            f"Welkin: Blender {bpy.app.version_string} is not supported: Welkin needs "
            f"Blender {'.'.join(map(str, MINIMUM_BLENDER))} or later (4.2 and later: "
            "install the Extension); nothing was registered"
        )
        return
    from . import blender

    blender.register()
    _registered = True


def unregister():
    global _registered
    if not _registered:
        return
    from . import blender

    blender.unregister()
    _registered = False


def __getattr__(name):
    """The compiled module's names, served from the add-on package: where `import welkin`
    finds this add-on first (Blender 3.x puts the add-ons folder on sys.path), scripts
    still get `welkin.Atmosphere.preset(...)`, `welkin.sky_radiance(...)` (native.py)."""
    import importlib
    import pathlib

    here = pathlib.Path(__file__).parent
    # Our own submodules are imported, never forwarded (the import system asks for them
    # here before it imports them).
    if name.startswith("_") or (here / f"{name}.py").exists() or (here / name).is_dir():
        raise AttributeError(name)
    native = importlib.import_module(__name__ + ".native")
    module = native.module()
    if module is None or not hasattr(module, name):
        raise AttributeError(
            f"module {__name__!r} has no attribute {name!r}"
            + (f" ({native.message()})" if module is None else "")
        )
    return getattr(module, name)
