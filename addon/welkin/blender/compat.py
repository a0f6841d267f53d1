# SPDX-License-Identifier: GPL-3.0-or-later
"""Differences between the Blender versions Welkin supports (3.4, 4.2 LTS, 4.5 LTS, 5.0-5.3),
in one place. The rest of the add-on calls these functions and never tests
bpy.app.version itself, so a new Blender is one edit here. Each function says which
versions differ and how (checked against each of them by tests/blender/). The one test
elsewhere is not a difference but the floor: the add-on's register() (addon/welkin/__init__.py)
refuses a Blender older than MINIMUM_BLENDER before it imports this package, whose
modules need 3.4's API to import at all.
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
    return "BLENDER_EEVEE_NEXT" if at_least(4, 2) and not at_least(5, 0) else "BLENDER_EEVEE"


def eevee_engine_ids():
    """Every id EEVEE has had (for COMPAT_ENGINES look-ups that must work everywhere)."""
    return ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT")


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
        if file_format == "OPEN_EXR_MULTILAYER":
            image_settings.media_type = "MULTI_LAYER_IMAGE"
        elif file_format == "FFMPEG":
            image_settings.media_type = "VIDEO"
        else:
            image_settings.media_type = "IMAGE"
    image_settings.file_format = file_format


def is_movie_output(render):
    """True when the render writes a movie (one file for all frames): `is_movie_format` in
    3.4-4.5, image_settings.media_type 'VIDEO' in 5.0+ (older builds without either: the
    movie file formats)."""
    if hasattr(render, "is_movie_format"):
        return render.is_movie_format
    settings = render.image_settings
    media = getattr(settings, "media_type", None)
    if media is not None:
        return media == "VIDEO"
    return settings.file_format in {"FFMPEG", "AVI_JPEG", "AVI_RAW"}


def sky_type_nishita():
    """Blender's physically based Sky Texture model: 'NISHITA' in 2.90-4.5; 5.0 renamed it
    'SINGLE_SCATTERING' (beside a new 'MULTIPLE_SCATTERING')."""
    items = bpy.types.ShaderNodeTexSky.bl_rna.properties["sky_type"].enum_items
    return "NISHITA" if "NISHITA" in items else "SINGLE_SCATTERING"


def compositor_output(tree):
    """The node whose input is the composited frame: the Composite node in 3.4-4.5, the
    tree's active Group Output in 5.0 (which has no Composite node). None if absent."""
    for node in tree.nodes:
        if node.bl_idname == "CompositorNodeComposite":
            return node
    outputs = [n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"]
    active = [n for n in outputs if getattr(n, "is_active_output", False)]
    return (active or outputs or [None])[0]


def cycles_vdb_placement():
    """Where Cycles puts a VDB grid's voxel ijk, as Welkin's VdbClouds placement names it:
    3.4-4.5 "blender" (the value at index ijk + 1/2, half a voxel off OpenVDB's
    convention), 5.0 "openvdb" (at index ijk, OpenVDB's own): measured against Cycles by
    tests/blender/test_cycles_clouds.py on each version."""
    return "openvdb" if at_least(5, 0) else "blender"


# --- Node groups, AOVs and the compositor (blender/aerial/frame.py) --------------------------------


def new_group_socket(group, name, in_out, socket_type):
    """A socket on a node group's interface: group.interface in 4.0+, inputs/outputs before."""
    if hasattr(group, "interface"):
        return group.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    sockets = group.inputs if in_out == "INPUT" else group.outputs
    return sockets.new(socket_type, name)


def clear_group_sockets(group):
    """Removes every socket of a node group's interface (4.0+) or its inputs and outputs."""
    if hasattr(group, "interface"):
        group.interface.clear()
    else:
        group.inputs.clear()
        group.outputs.clear()


def set_aov_name(node, name):
    """The AOV a Shader AOV Output node writes: `aov_name` in 4.0+, `name` in 3.x."""
    if hasattr(node, "aov_name"):
        node.aov_name = name
    else:
        node.name = name


def scene_compositor(scene):
    """The scene's compositing node tree, or None: scene.node_tree (when Use Nodes is on)
    before 5.0, scene.compositing_node_group in 5.0-5.2, the active compositor effect's
    group in 5.3+ (where compositing_node_group is deprecated and creates an effect when
    none exists: it is never read there)."""
    if hasattr(scene, "compositor_effects"):
        active = scene.compositor_effects.active
        return active.node_group if active is not None else None
    if hasattr(scene, "compositing_node_group"):
        return scene.compositing_node_group
    return scene.node_tree if scene.use_nodes else None


def _new_compositing_group(name, source):
    """A compositing node group `name` passing its frame to the Group Output: from a Render
    Layers node (`source` 'render', 5.0-5.2's scene compositor) or from the Group Input
    (`source` 'input', a 5.3 effect, which receives the frame of the effects before it)."""
    tree = bpy.data.node_groups.new(name, "CompositorNodeTree")
    new_group_socket(tree, "Image", "OUTPUT", "NodeSocketColor")
    out = tree.nodes.new("NodeGroupOutput")
    out.location = (600, 0)
    if source == "input":
        new_group_socket(tree, "Image", "INPUT", "NodeSocketColor")
        node = tree.nodes.new("NodeGroupInput")
        node.location = (-600, 300)
    else:
        node = tree.nodes.new("CompositorNodeRLayers")
    tree.links.new(node.outputs["Image"], out.inputs[0])
    return tree


def _add_effect(scene, name, index=None):
    """5.3+: a new compositor effect `name` with a new group of that name (frame in, frame
    out), at `index` of the stack (None: last), the active effect left as it was. Returns
    (tree, ('effect', name of the previously active effect or ''))."""
    effects = scene.compositor_effects
    active = effects.active.name if effects.active is not None else ""
    effect = effects.new(name=name)
    effect.node_group = _new_compositing_group(name, "input")
    if index is not None and effects[index].name != effect.name:
        with bpy.context.temp_override(scene=scene):
            bpy.ops.scene.move_compositor_effect_to_index(name=effect.name, index=index)
    if active:
        effects.active = effects[active]
    return effect.node_group, ("effect", active)


def ensure_scene_compositor(scene, name):
    """Turns compositing on: returns (tree, undo) where undo is what restore needs to put
    back: ('use_nodes', previous value) before 5.0 (Blender makes the default Render
    Layers -> Composite tree), ('created', None) in 5.0-5.2 when the scene had no
    compositing group (a new one, Render Layers -> Group Output, named `name`), ('effect',
    previously active effect) in 5.3+ when the scene had no effect (a new last one,
    Group Input -> Group Output), or ('kept', None)."""
    if hasattr(scene, "compositor_effects"):
        tree = scene_compositor(scene)
        return (tree, ("kept", None)) if tree is not None else _add_effect(scene, name)
    if hasattr(scene, "compositing_node_group"):
        tree = scene.compositing_node_group
        if tree is not None:
            return tree, ("kept", None)
        tree = _new_compositing_group(name, "render")
        scene.compositing_node_group = tree
        return tree, ("created", None)
    previous = scene.use_nodes
    scene.use_nodes = True
    return scene.node_tree, ("use_nodes", previous)


def _own_effect(scene, name):
    """5.3+: the compositor effect `name` whose group is also called `name` (the one
    _add_effect made), or None."""
    effect = scene.compositor_effects.get(name)
    if effect is not None and effect.node_group is not None and effect.node_group.name == name:
        return effect
    return None


def own_compositor(scene, name):
    """The compositing tree an add-on puts its nodes in, or None: the scene's compositor
    (scene_compositor) before 5.3; from 5.3 the group of the add-on's own effect `name`
    (ensure_own_compositor), so that the user's effects are never edited."""
    if not hasattr(scene, "compositor_effects"):
        return scene_compositor(scene)
    effect = _own_effect(scene, name)
    return effect.node_group if effect is not None else None


def ensure_own_compositor(scene, name):
    """own_compositor, made if missing: (tree, undo) as ensure_scene_compositor. From 5.3
    the add-on's effect goes first in the stack (it works on the rendered frame, before
    the user's effects), with a Render Layers node for the passes it reads."""
    if not hasattr(scene, "compositor_effects"):
        return ensure_scene_compositor(scene, name)
    tree = own_compositor(scene, name)
    if tree is not None:
        return tree, ("kept", None)
    tree, undo = _add_effect(scene, name, index=0)
    tree.nodes.new("CompositorNodeRLayers").location = (-600, -100)
    return tree, undo


def compositor_frame(tree, render_layers):
    """The socket carrying the frame that reaches `tree` from `render_layers`: the Group
    Input's Image in a 5.3 effect's group (the frame of the effects before it), the Render
    Layers' Image otherwise."""
    if hasattr(bpy.types, "SceneCompositorEffect"):
        for node in tree.nodes:
            if node.bl_idname == "NodeGroupInput" and "Image" in node.outputs:
                return node.outputs["Image"]
    return render_layers.outputs["Image"]


def restore_scene_compositor(scene, undo_kind, undo_value, created_name):
    """Undoes ensure_scene_compositor / ensure_own_compositor; `undo_value` as a string
    ('True'/'False' for use_nodes, the active effect's name for effect). 5.3+: the effect
    `created_name` goes whatever the kind (a file from 5.0-5.2 has 'created' or 'kept')."""
    if undo_kind == "use_nodes":
        scene.use_nodes = undo_value == "True"
    elif hasattr(scene, "compositor_effects"):
        effects = scene.compositor_effects
        effect = _own_effect(scene, created_name)
        if effect is not None:
            tree = effect.node_group
            effects.remove(effect)
            if tree.users == 0:
                bpy.data.node_groups.remove(tree)
        if undo_kind == "effect" and undo_value in effects:
            effects.active = effects[undo_value]
    elif undo_kind == "created" and hasattr(scene, "compositing_node_group"):
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
    node = tree.nodes.new("ShaderNodeMix")
    node.data_type = "RGBA"
    node.blend_type = blend_type
    node.clamp_result = False
    node.clamp_factor = True
    node.inputs[0].default_value = 1.0
    return (node, *_mix_sockets(node, "RGBA"))


def vector_mix(tree):
    """The shared Mix node (3.4+) in vector mode with one float factor, unclamped:
    (node, factor, input A, input B, output); the result is (1 - factor) A + factor B."""
    node = tree.nodes.new("ShaderNodeMix")
    node.data_type = "VECTOR"
    node.factor_mode = "UNIFORM"
    node.clamp_factor = False
    factor = next(s for s in node.inputs if s.name == "Factor" and s.type == "VALUE")
    return (node, factor, *_mix_sockets(node, "VECTOR"))


def compositor_mix(tree, blend_type):
    """A colour Mix node of the compositor, factor 1, unclamped: (node, input A, input B,
    output). CompositorNodeMixRGB before 5.0; the shared Mix node (rgba_mix) in 5.0+, where
    the compositor's own Mix node is gone."""
    if at_least(5, 0):
        return rgba_mix(tree, blend_type)
    node = tree.nodes.new("CompositorNodeMixRGB")
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
        material.surface_render_method = "DITHERED"
        if hasattr(material, "use_transparent_shadow"):
            material.use_transparent_shadow = True
        return
    material.blend_method = "HASHED"
    if hasattr(material, "shadow_method"):
        material.shadow_method = "HASHED"


def set_non_color(image):
    """Pixels read as data (no colour transform): 'Non-Color' in 3.4 to 5.x."""
    names = {item.identifier for item in image.colorspace_settings.bl_rna.properties["name"].enum_items}
    for name in ("Non-Color", "Non-Colour Data", "Raw"):
        if name in names:
            image.colorspace_settings.name = name
            return


def set_exr(image_settings, multilayer):
    """OpenEXR output, multilayer or not (set_file_format says how 5.0 differs)."""
    set_file_format(image_settings, "OPEN_EXR_MULTILAYER" if multilayer else "OPEN_EXR")


# --- Colour ---------------------------------------------------------------------------------

# Blender's working spaces (5.0+) -> the core's colour spaces (color_space.hpp), and the
# image colour space (OpenColorIO name) of each.
_WORKING_SPACES = {"Linear Rec.709": "rec709", "Linear Rec.2020": "rec2020", "ACEScg": "acescg"}
_IMAGE_SPACES = {
    "rec709": ("Linear Rec.709", "Linear"),
    "rec2020": ("Linear Rec.2020",),
    "acescg": ("ACEScg",),
}


def working_color_space():
    """The file's working colour space, as the core names it: Blender 5.0+ stores colours
    in bpy.data.colorspace.working_space (Linear Rec.709, Linear Rec.2020 or ACEScg, set by
    wm.set_working_color_space); 3.4-4.5 always in Linear Rec.709. A space the core does
    not write (none in 5.0-5.3) falls back to "rec709"."""
    colorspace = getattr(bpy.data, "colorspace", None)
    working = getattr(colorspace, "working_space", "Linear Rec.709")
    return _WORKING_SPACES.get(working, "rec709")


def image_color_space(image, color_space):
    """The name of `image`'s colour space setting for pixels in the core's `color_space`:
    "Linear Rec.709" ("Linear" in 3.4), "Linear Rec.2020", "ACEScg"."""
    names = {item.identifier for item in image.colorspace_settings.bl_rna.properties["name"].enum_items}
    for name in _IMAGE_SPACES[color_space]:
        if name in names:
            return name
    raise ValueError(f"color_space: this Blender has no image colour space for {color_space}")


def animates_nothing(anim_data):
    """True when the action assigned to `anim_data` (an ID's AnimData) holds no F-curve for
    that ID. Layered actions (4.4+; the legacy Action.fcurves is deprecated there and gone
    in 5.0) hold several IDs' curves, one slot each (keying a lamp's data puts its curves in
    its object's action, in a slot of their own): only this ID's slot counts."""
    action = anim_data.action
    layers = getattr(action, "layers", None)
    if layers is None:
        return len(action.fcurves) == 0
    slot = anim_data.action_slot
    return not any(
        len(bag.fcurves)
        for layer in layers
        for strip in layer.strips
        for bag in strip.channelbags
        if slot is None or bag.slot == slot
    )


# --- Compositor nodes of any version (blender/sky/night_vision.py) ------------------------------


def compositor_math(tree, operation):
    """A Math node in a compositing tree, unclamped: CompositorNodeMath before 5.0, the
    shared ShaderNodeMath from 5.0 (the compositor's own is gone). Inputs 0-2, output 0."""
    node = tree.nodes.new("ShaderNodeMath" if at_least(5, 0) else "CompositorNodeMath")
    node.operation = operation
    node.use_clamp = False
    return node


def compositor_value(tree, value):
    """A Value node holding `value` in a compositing tree: CompositorNodeValue before 5.0,
    ShaderNodeValue from 5.0."""
    node = tree.nodes.new("ShaderNodeValue" if at_least(5, 0) else "CompositorNodeValue")
    node.outputs[0].default_value = value
    return node


def set_gaussian_blur(node, radius_px):
    """A compositor Blur node as a Gaussian of `radius_px` pixels in x and y. 3.4-4.4:
    filter_type 'GAUSS', size_x/size_y (whole pixels) times the Size input (a factor,
    left at 1); 4.5: filter_type 'GAUSS' and the Size input, now a 2D vector of pixels;
    5.0+: the Type menu input 'Gaussian' and the Size input (pixels)."""
    size = node.inputs["Size"]
    if "Type" in node.inputs:
        node.inputs["Type"].default_value = "Gaussian"
    else:
        node.filter_type = "GAUSS"
    if size.type == "VECTOR":
        size.default_value = (radius_px, radius_px)
        return
    node.use_relative = False
    node.size_x = node.size_y = int(round(radius_px))
    size.default_value = 1.0


def gaussian_blur_radius(node):
    """The radius in pixels set_gaussian_blur gave `node`."""
    size = node.inputs["Size"]
    return float(size.default_value[0]) if size.type == "VECTOR" else float(node.size_x)


def ensure_output_compositor(scene, name):
    """The compositing tree whose output is the frame Blender writes, made if missing,
    for an add-on that works on the frame as it leaves the compositor: (tree, undo) as
    ensure_scene_compositor. Before 5.3 the scene's compositor (ensure_scene_compositor);
    from 5.3 the add-on's own effect `name`, last in the stack (fed the frame of the
    user's effects), so that the user's effects are never edited."""
    if not hasattr(scene, "compositor_effects"):
        return ensure_scene_compositor(scene, name)
    effect = _own_effect(scene, name)
    if effect is not None:
        return effect.node_group, ("kept", None)
    return _add_effect(scene, name)
