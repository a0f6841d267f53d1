"""Differences between the Blender versions Welkin supports (3.4, 4.2 LTS, 4.5 LTS, 5.0),
in one place. The rest of the add-on calls these functions and never tests
bpy.app.version itself, so a new Blender is one edit here. Each function says which
versions differ and how (checked against the real 3.4, 4.5 and 5.0 by tests/blender/).
"""
import os
import warnings

import bpy


def at_least(major, minor=0, patch=0):
    """True when the running Blender is this version or newer."""
    return bpy.app.version >= (major, minor, patch)


def eevee_engine_id():
    """The render engine id of EEVEE: 'BLENDER_EEVEE' in 3.x-4.1 (legacy EEVEE) and again
    from 5.0, 'BLENDER_EEVEE_NEXT' in 4.2-4.5 (EEVEE Next)."""
    return 'BLENDER_EEVEE_NEXT' if at_least(4, 2) and not at_least(5, 0) else 'BLENDER_EEVEE'


def eevee_engine_ids():
    """Every id EEVEE has had (for COMPAT_ENGINES look-ups that must work everywhere)."""
    return ('BLENDER_EEVEE', 'BLENDER_EEVEE_NEXT')


def world_node_tree(world):
    """The world's shader node tree, made to drive the world. 3.4-4.5: a world draws its
    nodes only with use_nodes on (switching it on creates the tree). 5.0: use_nodes is
    deprecated (a warning, removed in 6.0), every world has its tree and uses it."""
    if not at_least(5, 0):
        world.use_nodes = True
    elif world.node_tree is None:  # not seen in 5.0, where new worlds carry a tree
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            world.use_nodes = True
    return world.node_tree


def world_uses_nodes(world):
    """world.use_nodes where it means something (3.4-4.5); True from 5.0 on, where every
    world uses its node tree (reading use_nodes there warns)."""
    if at_least(5, 0):
        return True
    return world.use_nodes


def set_world_uses_nodes(world, value):
    """Puts world.use_nodes back (remove_sky): 3.4-4.5 only; from 5.0 it is a deprecated
    no-op and is left alone."""
    if not at_least(5, 0):
        world.use_nodes = bool(value)


def material_node_tree(material):
    """The material's shader node tree, made to drive the material. 3.4-4.5: a material
    renders its nodes only with use_nodes on (switching it on creates the tree). 5.0:
    Material.use_nodes is deprecated (a warning, removed in 6.0), every material has its
    tree and uses it, so it is not set."""
    if not at_least(5, 0):
        material.use_nodes = True
    elif material.node_tree is None:  # not seen in 5.0-5.3, where new materials carry a tree
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            material.use_nodes = True
    return material.node_tree


def material_uses_nodes(material):
    """Whether the material renders through its node tree: use_nodes with a tree in
    3.4-4.5; from 5.0 any material with a tree (reading use_nodes there warns)."""
    if material.node_tree is None:
        return False
    return True if at_least(5, 0) else material.use_nodes


def world_sun_threshold(world):
    """EEVEE Next (4.2+) turns world texels brighter than World.sun_threshold (default 10)
    into a sun light of its own. None where the setting does not exist (3.4-4.1: legacy
    EEVEE extracts no sun)."""
    return getattr(world, "sun_threshold", None)


def set_world_sun_threshold(world, value):
    """Sets World.sun_threshold where it exists (4.2+; 0 turns the extraction off);
    nothing in 3.4-4.1."""
    if value is not None and hasattr(world, "sun_threshold"):
        world.sun_threshold = value


def camera_panorama(camera_data):
    """The struct holding a panoramic camera's panorama_type and latitude/longitude range:
    the camera itself from 4.0 (Camera.panorama_type), Cycles' camera settings in 3.x
    (Camera.cycles.panorama_type). None when neither exists (Cycles disabled in 3.x)."""
    if hasattr(camera_data, "panorama_type"):
        return camera_data
    return getattr(camera_data, "cycles", None)


def set_file_format(image_settings, file_format):
    """Sets an output's file format by the 3.x/4.x name. 5.0 splits it: media_type
    ('IMAGE', 'MULTI_LAYER_IMAGE', 'VIDEO') first, then file_format, and multilayer EXR is
    media_type 'MULTI_LAYER_IMAGE' (file_format 'OPEN_EXR_MULTILAYER' is not accepted
    while the media type is 'IMAGE'). 3.4-4.5: file_format alone."""
    if hasattr(image_settings, "media_type"):
        if file_format == 'OPEN_EXR_MULTILAYER':
            image_settings.media_type = 'MULTI_LAYER_IMAGE'
        elif file_format == 'FFMPEG':
            image_settings.media_type = 'VIDEO'
        else:
            image_settings.media_type = 'IMAGE'
    image_settings.file_format = file_format


def sky_type_nishita():
    """Blender's physically based Sky Texture model: 'NISHITA' in 2.90-4.5; 5.0 renamed it
    'SINGLE_SCATTERING' (beside a new 'MULTIPLE_SCATTERING')."""
    items = bpy.types.ShaderNodeTexSky.bl_rna.properties['sky_type'].enum_items
    return 'NISHITA' if 'NISHITA' in items else 'SINGLE_SCATTERING'


def compositor_output(tree):
    """The node whose input is the composited frame: the Composite node in 3.4-4.5, the
    tree's active Group Output in 5.0 (which has no Composite node). None if absent."""
    for node in tree.nodes:
        if node.bl_idname == 'CompositorNodeComposite':
            return node
    outputs = [n for n in tree.nodes if n.bl_idname == 'NodeGroupOutput']
    active = [n for n in outputs if getattr(n, "is_active_output", False)]
    return (active or outputs or [None])[0]


def cycles_vdb_placement():
    """Where Cycles puts a VDB grid's voxel ijk, as Welkin's VdbClouds placement names it:
    3.4-4.5 "blender" (the value at index ijk + 1/2, half a voxel off OpenVDB's
    convention), 5.0 "openvdb" (at index ijk, OpenVDB's own): measured against Cycles by
    tests/blender/test_cycles_clouds.py on each version."""
    return "openvdb" if at_least(5, 0) else "blender"


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


def _mix_sockets(node, kind):
    """The shared Mix node's inputs A and B and its output of socket type `kind` (the node
    carries one set per data type; the others are hidden)."""
    a = next(s for s in node.inputs if s.name == "A" and s.type == kind)
    b = next(s for s in node.inputs if s.name == "B" and s.type == kind)
    out = next(s for s in node.outputs if s.type == kind)
    return a, b, out


def rgba_mix(tree, blend_type):
    """The shared Mix node (3.4+) in colour mode, factor 1 and clamped to [0, 1], result
    unclamped: (node, input A, input B, output). Shader trees in every version, the
    compositor from 5.0 (compositor_mix)."""
    node = tree.nodes.new('ShaderNodeMix')
    node.data_type = 'RGBA'
    node.blend_type = blend_type
    node.clamp_result = False
    node.clamp_factor = True
    node.inputs[0].default_value = 1.0
    return (node, *_mix_sockets(node, 'RGBA'))


def vector_mix(tree):
    """The shared Mix node (3.4+) in vector mode with one float factor, unclamped:
    (node, factor, input A, input B, output); the result is (1 - factor) A + factor B."""
    node = tree.nodes.new('ShaderNodeMix')
    node.data_type = 'VECTOR'
    node.factor_mode = 'UNIFORM'
    node.clamp_factor = False
    factor = next(s for s in node.inputs if s.name == "Factor" and s.type == 'VALUE')
    return (node, factor, *_mix_sockets(node, 'VECTOR'))


def compositor_mix(tree, blend_type):
    """A colour Mix node of the compositor, factor 1, unclamped: (node, input A, input B,
    output). CompositorNodeMixRGB before 5.0; the shared Mix node (rgba_mix) in 5.0+, where
    the compositor's own Mix node is gone."""
    if at_least(5, 0):
        return rgba_mix(tree, blend_type)
    node = tree.nodes.new('CompositorNodeMixRGB')
    node.blend_type = blend_type
    node.use_clamp = False
    node.inputs[0].default_value = 1.0
    return node, node.inputs[1], node.inputs[2], node.outputs[0]


def set_file_output_inputs(node, items):
    """A new File Output node's inputs, (name, socket type) pairs ('RGBA', 'FLOAT'): the
    node's file_output_items in 5.0+, its file_slots (always colour) before."""
    if hasattr(node, "file_output_items"):
        node.file_output_items.clear()
        for name, socket_type in items:
            node.file_output_items.new(socket_type, name)
        return
    node.file_slots.clear()
    for name, _socket_type in items:
        node.file_slots.new(name)


def file_output_path(node):
    """Where a File Output node writes, as set_file_output_path takes it: the path up to the
    frame number ('<dir>/<stem>', Blender appends '0001.exr')."""
    if hasattr(node, "file_output_items"):
        return os.path.join(node.directory, node.file_name.rstrip("#"))
    return node.base_path


def set_file_output_path(node, base):
    """Points a File Output node at `base` + frame + extension: base_path before 5.0; in 5.0
    directory and file_name, whose frame number comes from its '#' (none: no number).
    Writes nothing when it points there already (UI renders call this beside the
    interface)."""
    if file_output_path(node) == base:
        return
    if hasattr(node, "file_output_items"):
        node.directory, name = os.path.split(base)
        node.file_name = name + "####"
        return
    node.base_path = base


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


def set_exr(image_settings, multilayer):
    """OpenEXR output, multilayer or not (set_file_format says how 5.0 differs)."""
    set_file_format(image_settings, 'OPEN_EXR_MULTILAYER' if multilayer else 'OPEN_EXR')
