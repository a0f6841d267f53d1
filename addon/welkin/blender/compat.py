"""Differences between the Blender versions Welkin supports (3.4, 4.2 LTS, 4.5 LTS, 5.0),
in one place. The rest of the add-on calls these functions and never tests
bpy.app.version itself, so a new Blender is one edit here.
"""
import bpy


def at_least(major, minor=0, patch=0):
    """True when the running Blender is this version or newer."""
    return bpy.app.version >= (major, minor, patch)


def eevee_engine():
    """The render engine id of EEVEE: BLENDER_EEVEE_NEXT in 4.2-4.5 (EEVEE Next), else
    BLENDER_EEVEE (3.x, and 5.0, where EEVEE Next took the old id)."""
    return 'BLENDER_EEVEE_NEXT' if at_least(4, 2) and not at_least(5, 0) else 'BLENDER_EEVEE'
