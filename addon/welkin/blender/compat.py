"""Differences between the Blender versions Welkin supports (3.4, 4.2 LTS, 4.5 LTS, 5.0),
in one place. The rest of the add-on calls these functions and never tests
bpy.app.version itself, so a new Blender is one edit here.
"""
import bpy


def at_least(major, minor=0, patch=0):
    """True when the running Blender is this version or newer."""
    return bpy.app.version >= (major, minor, patch)
