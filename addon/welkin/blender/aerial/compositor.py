# SPDX-License-Identifier: GPL-3.0-or-later
"""The add-on's node in the scene's compositor for Aerial Perspective > Write Pass Files.

"Welkin Aerial Depth", a File Output node writing a multilayer EXR of the render's Image
and Depth (Z pass) for every frame, <base>welkin_render_<frame>.exr: the only way to read
the Z pass back in `blender -b` (the Viewer node cannot be read there). blender/aerial/pass_files.py computes
the pass files and the hazed frame from it in render_post. The frame itself is hazed in the
compositor by blender/aerial/frame.py's group; this node only writes.

The compositor tree is the one aerial_frame.install made sure of (compat.ensure_own_
compositor: the scene's compositor, or from Blender 5.3 Welkin's own compositor effect). The node is found by name; remove() takes it out. The user's nodes are never
touched.
"""

from .. import compat
from .frame import CREATED_TREE

DEPTH_NODE = "Welkin Aerial Depth"


def _render_layers(tree, scene):
    for node in tree.nodes:
        if node.bl_idname == "CompositorNodeRLayers" and node.scene in (None, scene):
            return node
    node = tree.nodes.new("CompositorNodeRLayers")
    node.location = (-600, 0)
    return node


def depth_node(scene):
    """Our File Output node, or None."""
    tree = compat.own_compositor(scene, CREATED_TREE)
    return tree.nodes.get(DEPTH_NODE) if tree is not None else None


def install(scene, settings, depth_base):
    """Adds (or updates) the depth node, writing to `depth_base` + frame + ".exr"; returns a
    list of warnings."""
    tree = compat.own_compositor(scene, CREATED_TREE)
    if tree is None:
        return ["no compositor: turn Aerial Perspective off and on"]
    warnings = []
    rl = _render_layers(tree, scene)
    out = tree.nodes.get(DEPTH_NODE)
    if out is None:
        out = tree.nodes.new("CompositorNodeOutputFile")
        out.name = out.label = DEPTH_NODE
        out.location = (rl.location.x + 300, rl.location.y - 350)
        compat.set_file_output_inputs(out, (("Image", "RGBA"), ("Depth", "FLOAT")))
    fmt = out.format
    compat.set_exr(fmt, multilayer=True)
    fmt.color_depth = "32"
    fmt.exr_codec = "ZIP"
    compat.set_file_output_path(out, depth_base)
    tree.links.new(rl.outputs["Image"], out.inputs["Image"])
    if "Depth" in rl.outputs:
        tree.links.new(rl.outputs["Depth"], out.inputs["Depth"])
    else:
        warnings.append("the render layer has no Depth output: enable View Layer > Passes > Z")
    settings.nodes_installed = True
    return warnings


def remove(scene, settings):
    """Takes the depth node out."""
    tree = compat.own_compositor(scene, CREATED_TREE)
    if tree is None:
        tree = getattr(scene, "node_tree", None)  # compositing turned off meanwhile (3.4-4.5)
    node = tree.nodes.get(DEPTH_NODE) if tree is not None else None
    if node is not None:
        tree.nodes.remove(node)
    settings.nodes_installed = False
