# SPDX-License-Identifier: GPL-3.0-or-later
"""Night vision for display: the compositor group "Welkin Night Vision" (Jensen et al.
2001's scotopic tone mapping; the formulas and constants are in addon/welkin/night_vision.py)
and the operators that add it to the scene's compositor and take it out again.

Added only when asked (welkin.add_night_vision, the Place and Time panel's button), the
group is one node between the frame that reaches the compositor's output and that output:
the Composite node (3.4-4.5) or the Group Output of the scene's compositing group
(5.0-5.2), and from 5.3, where the compositor is a stack of effects, the Group Output of
Welkin's own effect "Welkin Night Vision Compositing", last in the stack (fed the frame of the
user's effects). No node of the user's is changed or removed: only the link into the
output goes through the group, and welkin.remove_night_vision puts that link back,
removes the node (and the effect, or the compositing it turned on) and leaves the file's
compositing as it was. The world, the render layer's passes and File Output nodes keep
the physical values; only the composited frame changes.

The group is made of stock nodes only (Separate/Combine Color, Math, Value, Blur, Mix),
so a stock Blender without the add-on renders it (a farm's). Its constants, the
luminance scale (cd/m^2 per unit of the frame) and the acuity blur's radius, are set when
it is added: add it again after changing the sky's Exposure or the camera.
"""

import bpy

from ... import night_vision as nv
from .. import compat

GROUP = "Welkin Night Vision"
NODE = "Welkin Night Vision"
CREATED = "Welkin Night Vision Compositing"  # the compositing group or effect made when needed
MARK = "welkin_night_vision"  # custom property on our node (and group)
UNDO = "welkin_night_vision_undo"  # on the scene: what restore_scene_compositor needs
SCALE_NODE = "Luminance Scale"
BLUR_NODE = "Acuity Blur"
BUILT = 1  # the version of the group's nodes
TINY = 1e-30  # guards the divisions (the night's frame values go down to ~1e-7)


class NightVisionError(Exception):
    """A problem the user can fix; the operator reports it."""


# --- the group ---------------------------------------------------------------------------


class _Builder:
    """Math nodes in a compositing tree, laid out in columns."""

    def __init__(self, tree):
        self.tree = tree
        self.column = 0
        self.row = 0

    def _place(self, node):
        node.location = (-800 + 180 * self.column, 600 - 140 * self.row)
        self.row += 1
        if self.row > 7:
            self.row, self.column = 0, self.column + 1
        node.hide = True
        return node

    def math(self, operation, a, b=None, c=None, clamp=False):
        node = self._place(compat.compositor_math(self.tree, operation))
        node.use_clamp = clamp
        for k, v in enumerate((a, b, c)):
            if v is None:
                continue
            if isinstance(v, (int, float)):
                node.inputs[k].default_value = float(v)
            else:
                self.tree.links.new(v, node.inputs[k])
        return node.outputs[0]

    def dot(self, row, r, g, b):
        """row . (r, g, b) in three nodes: ((r m0) + g m1) + b m2."""
        acc = self.math("MULTIPLY", r, row[0])
        acc = self.math("MULTIPLY_ADD", g, row[1], acc)
        return self.math("MULTIPLY_ADD", b, row[2], acc)


def _build(group, color_space):
    """The nodes of the group, per pixel (addon/welkin/night_vision.py derives and cites
    them; Jensen et al. 2001's tone-mapping section, V after Ward Larson et al. 1997):
      (X, Y, Z) = M rgb                      M: the working space to XYZ (D65)
      L = k Y                                k: the "Luminance Scale" node, cd/m^2 per unit
      V = max(Y [1.33 (1 + (Y + Z) / X) - 1.68], 0)
      t = clamp((log10 max(L, 1e-12) + 2) / 2.6, 0, 1),  s = t^2 (3 - 2 t)
      x' = 0.25 + s (x - 0.25),  y' = 0.25 + s (y - 0.25),  (x, y) = (X, Y) / (X + Y + Z)
      Y' = s Y + (1 - s) 0.4468 V,  X' = x' Y' / y',  Z' = (1 - x' - y') Y' / y'
      out = s M^-1 (X', Y', Z') + (1 - s) Gauss_r(M^-1 (X', Y', Z'))
    with r the "Acuity Blur" node's radius in pixels; the divisions are guarded by 1e-30."""
    m = nv.rgb_to_xyz(color_space)
    m_inv = nv.inverse(m)
    gin = group.nodes.new("NodeGroupInput")
    gin.location = (-1300, 0)
    gout = group.nodes.new("NodeGroupOutput")
    gout.location = (1400, 0)
    sep = group.nodes.new("CompositorNodeSeparateColor")
    sep.mode = "RGB"
    sep.location = (-1100, 0)
    group.links.new(gin.outputs["Image"], sep.inputs["Image"])
    k = compat.compositor_value(group, nv.LUMENS_PER_WATT)
    k.name = k.label = SCALE_NODE
    k.location = (-1100, 300)
    b = _Builder(group)
    r, g, bl = sep.outputs["Red"], sep.outputs["Green"], sep.outputs["Blue"]
    # 1. XYZ in the frame's units, the luminance in cd/m^2, and V (Ward Larson et al. 1997).
    X, Y, Z = (b.dot(row, r, g, bl) for row in m)
    lum = b.math("MAXIMUM", b.math("MULTIPLY", Y, k.outputs[0]), nv.LUMINANCE_FLOOR)
    ratio = b.math("DIVIDE", b.math("ADD", Y, Z), b.math("MAXIMUM", X, TINY))
    V = b.math("MAXIMUM", b.math("MULTIPLY", Y, b.math("MULTIPLY_ADD", ratio, nv.V_A, nv.V_A - nv.V_B)), 0.0)
    # 2. The mesopic weight s: smoothstep of log10 L over [-2, 0.6].
    lo, hi = nv.MESOPIC_LOG10_CD_M2
    t = b.math("MULTIPLY_ADD", b.math("LOGARITHM", lum, 10.0), 1.0 / (hi - lo), -lo / (hi - lo), clamp=True)
    s = b.math("MULTIPLY", b.math("MULTIPLY", t, t), b.math("MULTIPLY_ADD", t, -2.0, 3.0))
    total = b.math("MAXIMUM", b.math("ADD", b.math("ADD", X, Y), Z), TINY)
    xb, yb = nv.BLUE_SHIFT_XY
    x2 = b.math("MULTIPLY_ADD", s, b.math("SUBTRACT", b.math("DIVIDE", X, total), xb), xb)
    y2 = b.math("MULTIPLY_ADD", s, b.math("SUBTRACT", b.math("DIVIDE", Y, total), yb), yb)
    scotopic = b.math("MULTIPLY", b.math("SUBTRACT", 1.0, s), b.math("MULTIPLY", V, nv.SCOTOPIC_SCALE))
    Y2 = b.math("MULTIPLY_ADD", s, Y, scotopic)
    q = b.math("DIVIDE", Y2, b.math("MAXIMUM", y2, TINY))
    X2 = b.math("MULTIPLY", x2, q)
    Z2 = b.math("MULTIPLY", b.math("SUBTRACT", b.math("SUBTRACT", 1.0, x2), y2), q)
    comb = group.nodes.new("CompositorNodeCombineColor")
    comb.mode = "RGB"
    comb.location = (900, 200)
    for n, row in enumerate(m_inv):
        group.links.new(b.dot(row, X2, Y2, Z2), comb.inputs[n])
    group.links.new(sep.outputs["Alpha"], comb.inputs["Alpha"])
    # 3. Acuity: the blurred frame where it is scotopic, the sharp one where photopic.
    blur = group.nodes.new("CompositorNodeBlur")
    blur.name = blur.label = BLUR_NODE
    blur.location = (1050, 350)
    compat.set_gaussian_blur(blur, 0.0)
    group.links.new(comb.outputs["Image"], blur.inputs["Image"])
    mix, a_in, b_in, out = compat.compositor_mix(group, "MIX")
    mix.location = (1200, 100)
    group.links.new(s, mix.inputs[0])
    group.links.new(blur.outputs["Image"], a_in)
    group.links.new(comb.outputs["Image"], b_in)
    group.links.new(out, gout.inputs["Image"])


def _our_group():
    """The file's group of ours (marked; a group of the user's that has the name is not it)."""
    return next(
        (g for g in bpy.data.node_groups if g.bl_idname == "CompositorNodeTree" and g.get(MARK)), None
    )


def night_group(color_space):
    """The group "Welkin Night Vision" for the working space `color_space`, built if
    missing, its nodes rebuilt if built for another space or version (its interface, one
    Image in and out, is kept, so the node using it keeps its links)."""
    key = f"{BUILT}/{color_space}"
    group = _our_group()
    if group is not None and group.get(MARK) == key:
        return group
    if group is None:
        group = bpy.data.node_groups.new(GROUP, "CompositorNodeTree")
        compat.new_group_socket(group, "Image", "INPUT", "NodeSocketColor")
        compat.new_group_socket(group, "Image", "OUTPUT", "NodeSocketColor")
    else:
        group.nodes.clear()
    group[MARK] = key
    _build(group, color_space)
    return group


def set_constants(group, luminance_scale, blur_px):
    group.nodes[SCALE_NODE].outputs[0].default_value = luminance_scale
    compat.set_gaussian_blur(group.nodes[BLUR_NODE], blur_px)


# --- the scene's settings ----------------------------------------------------------------


def scene_luminance_scale(scene):
    """cd/m^2 per unit of the frame: 683 over the sky's Exposure."""
    settings = getattr(scene.world, "welkin", None) if scene.world is not None else None
    return nv.luminance_scale(settings.exposure if settings is not None else 1.0)


def scene_blur_px(scene):
    """The acuity blur's radius for the scene camera and the render's width."""
    camera = scene.camera
    if camera is None or camera.type != "CAMERA":
        return 0.0
    width = scene.render.resolution_x * scene.render.resolution_percentage / 100.0
    data = camera.data
    longitude = None
    if data.type == "PANO":
        pano = compat.camera_panorama(data)
        if pano is not None and hasattr(pano, "longitude_max"):
            longitude = pano.longitude_max - pano.longitude_min
    return nv.acuity_blur_px(nv.pixels_per_degree(data.type, data.angle_x, width, longitude))


# --- in the compositor -------------------------------------------------------------------


def _tree(scene):
    tree = compat.own_compositor(scene, CREATED)
    if tree is None and not hasattr(scene, "compositor_effects"):
        tree = getattr(scene, "node_tree", None)  # compositing turned off meanwhile (3.4-4.5)
    return tree


def _our_nodes(tree):
    return [n for n in tree.nodes if n.bl_idname == "CompositorNodeGroup" and n.get(MARK)]


def night_node(scene):
    """Our node in the scene's compositor, or None."""
    tree = _tree(scene)
    nodes = _our_nodes(tree) if tree is not None else []
    return nodes[0] if nodes else None


def add(scene, blur_px=None):
    """Puts the group before the compositor's output (or updates its constants when it is
    there); `blur_px` None: from the camera. Returns the node."""
    scale = scene_luminance_scale(scene)
    blur = scene_blur_px(scene) if blur_px is None else float(blur_px)
    if not 0.0 <= blur <= 1000.0:
        raise NightVisionError(f"acuity_blur_px: {blur} is outside [0, 1000] pixels")
    node = night_node(scene)
    if node is not None:
        set_constants(night_group(compat.working_color_space()), scale, blur)
        return node
    tree, (kind, value) = compat.ensure_output_compositor(scene, CREATED)
    output = compat.compositor_output(tree)
    target = output.inputs[0] if output is not None and len(output.inputs) else None
    if target is None or not target.links:
        compat.restore_scene_compositor(scene, kind, str(value), CREATED)
        where = (
            "no Composite or Group Output node" if output is None else f"nothing linked into '{output.name}'"
        )
        raise NightVisionError(f"the scene's compositor has {where}: link the frame to its output first")
    group = night_group(compat.working_color_space())
    set_constants(group, scale, blur)
    source = target.links[0].from_socket
    node = tree.nodes.new("CompositorNodeGroup")
    node.node_tree = group
    node.name = node.label = NODE
    node[MARK] = True
    node.location = (output.location.x - 220, output.location.y + 160)
    tree.links.new(source, node.inputs[0])
    tree.links.new(node.outputs[0], target)
    if UNDO not in scene:
        scene[UNDO] = f"{kind}\t{value}"
    return node


def remove(scene):
    """Takes our node out, links what fed it to what it fed, and undoes what add() turned
    on (compositing, the effect). Returns whether there was anything to remove."""
    tree = _tree(scene)
    found = False
    for node in _our_nodes(tree) if tree is not None else []:
        found = True
        inputs = node.inputs[0].links
        source = inputs[0].from_socket if inputs else None
        targets = [link.to_socket for link in node.outputs[0].links]
        tree.nodes.remove(node)
        if source is not None:
            for socket in targets:
                tree.links.new(source, socket)
    if UNDO in scene:
        kind, value = str(scene[UNDO]).split("\t", 1)
        compat.restore_scene_compositor(scene, kind, value, CREATED)
        del scene[UNDO]
        found = True
    group = _our_group()
    if group is not None and group.users == 0:
        bpy.data.node_groups.remove(group)
    return found


# --- operators ---------------------------------------------------------------------------


class WELKIN_OT_add_night_vision(bpy.types.Operator):
    """Show the frame as the dark-adapted eye sees it (Jensen et al. 2001): a compositor
    group before the output; the rendered passes and the world keep their physical values"""

    bl_idname = "welkin.add_night_vision"
    bl_label = "Add Night Vision"
    bl_options = {"REGISTER", "UNDO"}

    acuity_blur_px: bpy.props.FloatProperty(
        name="Acuity Blur (px)",
        default=-1.0,
        min=-1.0,
        max=1000.0,
        description="Radius of the blur where the eye sees with its rods alone, in pixels "
        "(-1: from the camera's angle and the render width, for the eye's acuity at 0.01 cd/m2)",
    )

    def execute(self, context):
        scene = context.scene
        try:
            node = add(scene, None if self.acuity_blur_px < 0.0 else self.acuity_blur_px)
        except (NightVisionError, ValueError) as error:
            self.report({"ERROR"}, f"Welkin: {error}")
            print(f"Welkin: error: {error}")
            return {"CANCELLED"}
        group = node.node_tree
        blur = compat.gaussian_blur_radius(group.nodes[BLUR_NODE])
        scale = group.nodes[SCALE_NODE].outputs[0].default_value
        self.report(
            {"INFO"},
            f"Welkin: night vision before the compositor's output ({scale:.4g} cd/m2 per unit, "
            f"acuity blur {blur:.3g} px)",
        )
        return {"FINISHED"}


class WELKIN_OT_remove_night_vision(bpy.types.Operator):
    """Take the night-vision group out of the compositor, restoring its links"""

    bl_idname = "welkin.remove_night_vision"
    bl_label = "Remove Night Vision"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        if not remove(context.scene):
            self.report({"INFO"}, "Welkin: no night vision in this scene's compositor")
        return {"FINISHED"}


classes = (WELKIN_OT_add_night_vision, WELKIN_OT_remove_night_vision)
