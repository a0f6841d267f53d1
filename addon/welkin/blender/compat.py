"""Differences between the Blender versions Welkin supports (3.4, 4.2 LTS, 4.5 LTS, 5.0),
in one place. The rest of the add-on calls these functions and never tests
bpy.app.version itself, so a new Blender is one edit here.
"""
import bpy


def at_least(major, minor=0, patch=0):
    """True when the running Blender is this version or newer."""
    return bpy.app.version >= (major, minor, patch)


def set_hashed_transparency(material):
    """EEVEE shows and shadows `material`'s transparency stochastically: blend and shadow
    modes HASHED (EEVEE Legacy, up to 4.1); from 4.2 (EEVEE Next) dithered rendering with
    transparent shadows (surface_render_method, use_transparent_shadow)."""
    if hasattr(material, "surface_render_method"):
        material.surface_render_method = 'DITHERED'
        if hasattr(material, "use_transparent_shadow"):
            material.use_transparent_shadow = True
        return
    material.blend_method = 'HASHED'
    if hasattr(material, "shadow_method"):
        material.shadow_method = 'HASHED'


def set_non_color(image):
    """Pixels read as data (no colour transform): 'Non-Color' in 3.4 to 5.x."""
    names = {item.identifier for item in
             image.colorspace_settings.bl_rna.properties['name'].enum_items}
    for name in ("Non-Color", "Non-Colour Data", "Raw"):
        if name in names:
            image.colorspace_settings.name = name
            return
