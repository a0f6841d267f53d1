"""Differences between the Blender versions Welkin supports (3.4, 4.2 LTS, 4.5 LTS, 5.0),
in one place. The rest of the add-on calls these functions and never tests
bpy.app.version itself, so a new Blender is one edit here.
"""
import bpy


def at_least(major, minor=0, patch=0):
    """True when the running Blender is this version or newer."""
    return bpy.app.version >= (major, minor, patch)


# --- Node groups, AOVs and the compositor (aerial_frame.py) --------------------------------

def new_group_socket(group, name, in_out, socket_type):
    """A socket on a node group's interface: group.interface in 4.0+, inputs/outputs before."""
    if hasattr(group, "interface"):
        return group.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    sockets = group.inputs if in_out == 'INPUT' else group.outputs
    return sockets.new(socket_type, name)


def set_aov_name(node, name):
    """The AOV a Shader AOV Output node writes: `aov_name` in 4.0+, `name` in 3.x."""
    if hasattr(node, "aov_name"):
        node.aov_name = name
    else:
        node.name = name


def scene_compositor(scene):
    """The scene's compositing node tree, or None: scene.compositing_node_group in 5.0+,
    scene.node_tree (when Use Nodes is on) before."""
    if hasattr(scene, "compositing_node_group"):
        return scene.compositing_node_group
    return scene.node_tree if scene.use_nodes else None


def ensure_scene_compositor(scene, name):
    """Turns compositing on: returns (tree, undo) where undo is what remove needs to put back:
    ('use_nodes', previous value) before 5.0 (Blender makes the default Render Layers ->
    Composite tree), ('created', None) in 5.0+ when the scene had no compositing group (a new
    one, Render Layers -> Group Output, named `name`), or ('kept', None)."""
    if hasattr(scene, "compositing_node_group"):
        tree = scene.compositing_node_group
        if tree is not None:
            return tree, ('kept', None)
        tree = bpy.data.node_groups.new(name, 'CompositorNodeTree')
        new_group_socket(tree, "Image", 'OUTPUT', 'NodeSocketColor')
        rl = tree.nodes.new('CompositorNodeRLayers')
        out = tree.nodes.new('NodeGroupOutput')
        out.location = (600, 0)
        tree.links.new(rl.outputs["Image"], out.inputs[0])
        scene.compositing_node_group = tree
        return tree, ('created', None)
    previous = scene.use_nodes
    scene.use_nodes = True
    return scene.node_tree, ('use_nodes', previous)


def restore_scene_compositor(scene, undo_kind, undo_value, created_name):
    if undo_kind == 'use_nodes':
        scene.use_nodes = bool(undo_value)
    elif undo_kind == 'created' and hasattr(scene, "compositing_node_group"):
        tree = scene.compositing_node_group
        if tree is not None and tree.name == created_name:
            scene.compositing_node_group = None
            bpy.data.node_groups.remove(tree)


def compositor_mix(tree, blend_type):
    """A colour Mix node of the compositor, factor 1, unclamped: (node, input A, input B,
    output). CompositorNodeMixRGB before 5.0; the shared Mix node (RGBA) in 5.0+, where the
    compositor's own Mix node is gone."""
    if at_least(5, 0):
        node = tree.nodes.new('ShaderNodeMix')
        node.data_type = 'RGBA'
        node.blend_type = blend_type
        node.clamp_result = False
        node.clamp_factor = True
        node.inputs[0].default_value = 1.0
        a = next(s for s in node.inputs if s.name == "A" and s.type == 'RGBA')
        b = next(s for s in node.inputs if s.name == "B" and s.type == 'RGBA')
        out = next(s for s in node.outputs if s.type == 'RGBA')
        return node, a, b, out
    node = tree.nodes.new('CompositorNodeMixRGB')
    node.blend_type = blend_type
    node.use_clamp = False
    node.inputs[0].default_value = 1.0
    return node, node.inputs[1], node.inputs[2], node.outputs[0]


def eevee_engine():
    """The identifier of EEVEE: BLENDER_EEVEE_NEXT in 4.2-4.5, BLENDER_EEVEE otherwise."""
    return 'BLENDER_EEVEE_NEXT' if at_least(4, 2) and not at_least(5, 0) else 'BLENDER_EEVEE'


def set_exr(image_settings, multilayer):
    """OpenEXR output, multilayer or not: file_format OPEN_EXR_MULTILAYER or OPEN_EXR; in 5.0+
    the media type (MULTI_LAYER_IMAGE or IMAGE) is chosen first and limits the formats."""
    if hasattr(image_settings, "media_type"):
        image_settings.media_type = 'MULTI_LAYER_IMAGE' if multilayer else 'IMAGE'
    image_settings.file_format = 'OPEN_EXR_MULTILAYER' if multilayer else 'OPEN_EXR'
