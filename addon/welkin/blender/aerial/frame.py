# SPDX-License-Identifier: GPL-3.0-or-later
"""Aerial perspective in the rendered frame itself (Cycles and EEVEE; F12, -f, -a, any -o).

What the add-on adds while Scene.welkin_aerial is on, each found by name and taken out by
remove() exactly:
  * the frame's aerial-perspective table as float images, baked again whenever the frame's
    camera, sun or atmosphere change (frame_change_post, with the render's own depsgraph,
    so each frame of -a is hazed for its own state), in the form the render engine reads
    fastest (aerial_table.py has both layouts):
      Cycles: the camera's screen table (welkin.aerial_screen_table), three images
      "Welkin Aerial Inscatter", "... Inscatter Step" and "... Opacity";
      EEVEE: the direction table (welkin.aerial_table from the camera's position), one
      atlas "Welkin Aerial Table";
  * the shader node group "Welkin Aerial" and one node of it in every material that uses
    nodes ("Welkin Aerial" node, unlinked): it reads where the shading point is seen
    (Cycles: Camera Data > View Vector, or Texture Coordinate > Window for other than
    perspective cameras, and View Distance, or View Z Depth for orthographic ones; EEVEE:
    Geometry > Incoming and View Distance), samples the table and writes two shader AOVs,
    Welkin_AerialInscatter (L) and Welkin_AerialOpacity (1 - T, so that a pixel no
    material writes, the sky, means T = 1);
  * those two AOVs on every view layer (Blender turns '.' in AOV names into '_');
  * in the compositor, for each Render Layers node of the scene, the node group "Welkin
    Aerial Haze" fed by its Image and the two AOVs, computing
    Image x T + Inscatter; every link that left the Render Layers' Image now leaves the
    group's Image (so the Composite / Group Output node, File Output nodes and the user's
    own nodes see the hazed frame), and the group's outputs Welkin.AerialInscatter and
    Welkin.AerialTransmittance are the passes.
The materials' shading and the user's nodes are not touched otherwise.
"""

import json
import math

import bpy

from ... import aerial_table as tab
from .. import compat

IMAGE = "Welkin Aerial Table"
SCREEN_IMAGES = ("Welkin Aerial Inscatter", "Welkin Aerial Inscatter Step", "Welkin Aerial Opacity")
OLD_IMAGES = ("Welkin Aerial Opacity Step",)  # an earlier form's, removed with the rest
SHADER_GROUP = "Welkin Aerial"
SHADER_NODE = "Welkin Aerial"
COMP_GROUP = "Welkin Aerial Haze"
COMP_NODE = "Welkin Aerial Haze"
CREATED_TREE = "Welkin Compositing"
AOV_INSCATTER = "Welkin_AerialInscatter"
AOV_OPACITY = "Welkin_AerialOpacity"
AOVS = (AOV_INSCATTER, AOV_OPACITY)
MARK = "welkin_aerial"  # custom property on our nodes: what they belong to
LATTICE = "welkin_aerial_lattice"  # on the shader group: the bake its screen constants are for
MAX_DISTANCE_NODE = "Max Distance"
LINEAR_DISTANCE_NODE = "Linear Distance"
SLICE_NODE, OFFSET_NODE, SCREEN_NODE = "Slice", "Slice Offset", "Screen"  # the screen form's constants
# Nodes that keep the render layer's own Image: the pass files' depth/image writer.
KEEP_UNHAZED = ("Welkin Aerial Depth",)


# --- the table image ---------------------------------------------------------------------


def table_image():
    image = bpy.data.images.get(IMAGE)
    if image is not None and tuple(image.size) != (tab.WIDTH, tab.HEIGHT):
        bpy.data.images.remove(image)
        image = None
    if image is None:
        image = bpy.data.images.new(IMAGE, tab.WIDTH, tab.HEIGHT, alpha=True, float_buffer=True)
        image.colorspace_settings.name = "Non-Color"
        image[MARK] = True
    return image


def bake(scene, module, scene_text, scale_length, baked):
    """Bakes the table of the frame described by `scene_text` into the images in the form
    the scene's render engine reads (Cycles: the screen table, else the direction table)
    and sets the node group's constants; the images are left alone when `baked` (image
    name -> key of what it holds) says they hold this frame's table already."""
    description = json.loads(scene_text)
    if scene.render.engine == "CYCLES":
        _bake_screen(scene, module, scene_text, description, scale_length, baked)
        return
    atmosphere = description["atmosphere"]
    max_distance_bu = (
        tab.max_distance_m(
            description["camera"].get("clip_end_m", 1e6),
            atmosphere["bottom_radius_m"],
            atmosphere["top_radius_m"],
        )
        / scale_length
    )
    key = f"{scene_text}|{max_distance_bu!r}|{scale_length!r}"
    image = table_image()
    group = shader_group(FETCH_CLOSEST)
    _set(group.nodes[MAX_DISTANCE_NODE].outputs[0], max_distance_bu)
    _set(group.nodes[LINEAR_DISTANCE_NODE].outputs[0], tab.LINEAR_DISTANCE_M / scale_length)
    if baked.get(image.name) == key:
        return
    t = module.aerial_table(
        scene_text,
        azimuths=tab.AZIMUTHS,
        elevations=tab.ELEVATIONS,
        slices=tab.SLICES,
        max_distance_m=max_distance_bu * scale_length,
        linear_distance_m=tab.LINEAR_DISTANCE_M,
        steps_per_slice=tab.STEPS_PER_SLICE,
    )
    pixels = tab.atlas_pixels(t["inscatter"], t["optical_depth"])
    image.pixels.foreach_set(pixels.ravel())
    image.update()
    baked[image.name] = key


def screen_request(scene, description, scale_length):
    """What the frame's screen table is asked for (welkin.aerial_screen_table's keywords):
    the coordinate the group reads for the camera, the margins Cycles' pixel filter needs
    at the render size (`description`: the frame's scene JSON, parsed), the scene unit."""
    camera, res = description["camera"], description["resolution"]
    width = max(1, res["x"] * res.get("percentage", 100) // 100)
    height = max(1, res["y"] * res.get("percentage", 100) // 100)
    cycles = getattr(scene, "cycles", None)
    filter_px = float(getattr(cycles, "filter_width", 1.5)) if cycles is not None else 1.5
    margin_x, margin_y = tab.screen_margins(width, height, filter_px)
    kind = camera.get("type", "PERSP")
    return dict(
        coordinate="view_vector" if kind == "PERSP" else "window",
        columns=tab.SCREEN_COLUMNS,
        rows=tab.SCREEN_ROWS,
        margin_x=margin_x,
        margin_y=margin_y,
        unit_m=float(scale_length),
        ratio=tab.SCREEN_RATIO,
        steps_per_slice=tab.SCREEN_STEPS_PER_SLICE,
    ), kind == "ORTHO"


def _set(socket, value):
    """Sets a node socket's default value only when it changes (a change recompiles)."""
    current = socket.default_value
    if isinstance(value, tuple):
        if any(abs(a - b) > 1e-9 * max(1.0, abs(b)) for a, b in zip(current, value)):
            socket.default_value = value
    elif abs(current - value) > 1e-9 * max(1.0, abs(value)):
        socket.default_value = value


def _bake_screen(scene, module, scene_text, description, scale_length, baked):
    request, ortho = screen_request(scene, description, scale_length)
    group = shader_group(FETCH_SCREEN)
    # What the group reads: the View Vector (perspective) or the Window coordinate, and the
    # distance the slices measure: View Distance from the camera, or for an orthographic
    # camera (whose rays start on its plane) View Z Depth.
    cam = next(n for n in group.nodes if n.bl_idname == "ShaderNodeCameraData")
    coords = next(n for n in group.nodes if n.bl_idname == "ShaderNodeTexCoord")
    _link(
        group,
        cam.outputs["View Vector"] if request["coordinate"] == "view_vector" else coords.outputs["Window"],
        group.nodes[SCREEN_NODE].inputs[0],
    )
    _link(group, cam.outputs["View Z Depth" if ortho else "View Distance"], group.nodes[SLICE_NODE].inputs[0])
    key = f"{scene_text}|{sorted(request.items())!r}"
    if all(baked.get(name) == key for name in SCREEN_IMAGES) and group.get(LATTICE) == key:
        return
    t = module.aerial_screen_table(scene_text, **request)
    lattice = tab.ScreenLattice(t["lattice"])
    # The lattice's constants (aerial_table.screen_coordinates).
    _set(group.nodes[SLICE_NODE].inputs[1], lattice.log_base)
    _set(group.nodes[OFFSET_NODE].inputs[1], lattice.snap)
    _set(group.nodes[SCREEN_NODE].inputs[1], lattice.scale)
    group[LATTICE] = key
    for name, pixels in zip(SCREEN_IMAGES, t["textures"]):
        image = screen_image(name, lattice.columns, lattice.height)
        image.pixels.foreach_set(pixels.reshape(-1))
        image.update()
        baked[name] = key


def _link(group, socket, into):
    """Links `socket` into the input `into` unless it is linked so already (a change
    recompiles the shaders)."""
    if not into.links or into.links[0].from_socket != socket:
        group.links.new(socket, into)


def screen_image(name, width, height):
    """One of the screen table's images, width x height (resized in place, so that the
    group's texture nodes keep it)."""
    image = bpy.data.images.get(name)
    if image is None:
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
        image.colorspace_settings.name = "Non-Color"  # data: no view transform
        image[MARK] = True
    elif tuple(image.size) != (width, height):
        image.scale(width, height)
    if image.alpha_mode != "CHANNEL_PACKED":  # alpha holds a step, not coverage (also in an
        image.alpha_mode = "CHANNEL_PACKED"  # earlier form's image of this name)
    return image


# --- the material node group -------------------------------------------------------------


def _math(group, op, a=None, b=None, c=None, x=0, y=0, clamp=False):
    node = group.nodes.new("ShaderNodeMath")
    node.operation = op
    node.use_clamp = clamp
    node.location = (x, y)
    for k, v in enumerate((a, b, c)):
        if v is None:
            continue
        if isinstance(v, (int, float)):
            node.inputs[k].default_value = float(v)
        else:
            group.links.new(v, node.inputs[k])
    return node.outputs[0]


def _vmath(group, op, a, b=None, scale=None, x=0, y=0):
    node = group.nodes.new("ShaderNodeVectorMath")
    node.operation = op
    node.location = (x, y)
    for k, v in enumerate((a, b)):
        if v is None:
            continue
        if isinstance(v, tuple):
            node.inputs[k].default_value = v
        else:
            group.links.new(v, node.inputs[k])
    if scale is not None:
        if isinstance(scale, (int, float)):
            node.inputs["Scale"].default_value = float(scale)
        else:
            group.links.new(scale, node.inputs["Scale"])
    return node.outputs["Vector"]


# How the group reads the table:
#   FETCH_SCREEN   Cycles: the screen table (aerial_table.screen_lookup), 12 nodes at
#                  every camera-ray sample (Cycles evaluates them there): the View Vector
#                  (or Window) and tau, one logarithm of the distance, address the slice's
#                  texels in a snap and one multiply-add, three 'Linear' fetches of
#                  repeating textures (Cycles filters without mipmaps; the lattice wraps
#                  outside the frame) read each pass's line through the slice as its values
#                  at tau = 0 and 1, a Combine Color gathers the opacity's second value
#                  from the alphas, and two Mix nodes read the lines at tau (one Cycles
#                  instruction each, where a vector multiply-add takes two and a conversion
#                  of tau to a vector);
#   FETCH_CLOSEST  EEVEE: the direction table in sixteen 'Closest' fetches filtered by
#                  the group's own nodes. EEVEE filters a 'Linear' image with mipmaps
#                  chosen from screen-space derivatives, and v jumps by a whole tile where
#                  the distance slice changes, which would blur the table there.
# The group takes the form of the engine of the scene whose table is baked (bake()); a
# change of engine rebuilds it in place (the materials' nodes keep using it).
FETCH_SCREEN, FETCH_CLOSEST = "screen", "closest"


def _layout(fetch):
    if fetch == FETCH_SCREEN:
        return f"screen/{len(SCREEN_IMAGES)}/5"  # the form and the version of its nodes
    return f"{tab.HEIGHT}x{tab.WIDTH}/{fetch}/3"  # the table's layout, the fetch, the nodes: the version


def _screen_nodes(group):
    """The screen form (aerial_table.screen_coordinates and screen_lookup in nodes); the
    constants, and which coordinate and distance feed it, are the bake's (_bake_screen).
    Cycles leaves out the unlinked one of Texture Coordinate and View Vector."""
    coords = group.nodes.new("ShaderNodeTexCoord")
    coords.location = (-800, 300)
    cam = group.nodes.new("ShaderNodeCameraData")
    cam.location = (-800, -100)
    tau = _math(group, "LOGARITHM", cam.outputs["View Distance"], tab.SCREEN_RATIO**100, x=-600, y=-200)
    tau.node.name = tau.node.label = SLICE_NODE
    offset = _vmath(group, "SNAP", tau, (1.0, 0.01, 1.0), x=-400, y=-100)
    offset.node.name = offset.node.label = OFFSET_NODE
    uv = _vmath(group, "MULTIPLY_ADD", cam.outputs["View Vector"], (1.0, 1.0, 0.0), x=-200, y=100)
    uv.node.name = uv.node.label = SCREEN_NODE
    group.links.new(offset, uv.node.inputs[2])
    texs = []
    for n, name in enumerate(SCREEN_IMAGES):
        tex = group.nodes.new("ShaderNodeTexImage")
        tex.location = (0, 400 - 300 * n)
        tex.image = bpy.data.images.get(name) or screen_image(name, 1, 1)  # sized by the bake
        tex.interpolation = "Linear"
        tex.extension = "REPEAT"
        group.links.new(uv, tex.inputs["Vector"])
        texs.append(tex)
    # The opacity at tau = 1, from the alphas: Combine Color (one instruction; Combine XYZ
    # takes one per component).
    far = group.nodes.new("ShaderNodeCombineColor")
    far.location = (250, -500)
    for n, tex in enumerate(texs):
        group.links.new(tex.outputs["Alpha"], far.inputs[n])
    outputs = []
    for near, at_one, y in (
        (texs[0].outputs["Color"], texs[1].outputs["Color"], 300),
        (texs[2].outputs["Color"], far.outputs[0], -200),
    ):
        node, factor, a, b, out = compat.vector_mix(group)
        node.location = (450, y)
        group.links.new(tau, factor)
        group.links.new(near, a)
        group.links.new(at_one, b)
        outputs.append(out)
    for name, socket, y in ((AOV_INSCATTER, outputs[0], 300), (AOV_OPACITY, outputs[1], -200)):
        aov = group.nodes.new("ShaderNodeOutputAOV")
        compat.set_aov_name(aov, name)
        aov.location = (700, y)
        group.links.new(socket, aov.inputs["Color"])


def _closest_view(group):
    """The closest form's coordinates of the hit: u, the nearer slice's v0, the slices' weight w."""
    E, S, Hh = tab.ELEVATIONS, tab.SLICES, float(tab.HEIGHT)
    geo = group.nodes.new("ShaderNodeNewGeometry")
    geo.location = (-1400, 200)
    cam = group.nodes.new("ShaderNodeCameraData")
    cam.location = (-1400, -300)
    dmax = group.nodes.new("ShaderNodeValue")
    dmax.name = dmax.label = MAX_DISTANCE_NODE
    dmax.location = (-1400, -500)
    dmax.outputs[0].default_value = 1e6
    d0 = group.nodes.new("ShaderNodeValue")
    d0.name = d0.label = LINEAR_DISTANCE_NODE
    d0.location = (-1400, -650)
    d0.outputs[0].default_value = tab.LINEAR_DISTANCE_M
    # Every node below runs at every camera-ray hit, so constants are folded into as few
    # nodes as the arithmetic allows (Cycles folds nodes whose inputs are all constant: the
    # Value nodes' expressions cost nothing per hit).
    # The view direction is -Incoming. u = atan2(y, x) / 2 pi + 1/2 of the view direction
    # is atan2 of Incoming's components / 2 pi, give or take 1: the same texel with REPEAT.
    sep = group.nodes.new("ShaderNodeSeparateXYZ")
    sep.location = (-1000, 200)
    group.links.new(geo.outputs["Incoming"], sep.inputs[0])
    u = _math(
        group,
        "MULTIPLY",
        _math(group, "ARCTAN2", sep.outputs["Y"], sep.outputs["X"], x=-800, y=400),
        1.0 / (2.0 * math.pi),
        x=-600,
        y=400,
    )
    # The view's elevation theta = -asin(Incoming.z); e = sign(theta) sqrt(|theta| 2 / pi) / 2
    # + 1/2; the texel row in its tile, row = e (E - 1) + 1/2, over H:
    # rowh = -sign(t) sqrt(|t|) sqrt(2 / pi) (E - 1) / (2 H) + E / (2 H), t = asin(Incoming.z).
    t = _math(group, "ARCSINE", sep.outputs["Z"], x=-800, y=200)
    root = _math(group, "SQRT", _math(group, "ABSOLUTE", t, x=-600, y=200), x=-400, y=200)
    rowh = _math(
        group,
        "MULTIPLY_ADD",
        _math(group, "MULTIPLY", _math(group, "SIGN", t, x=-400, y=100), root, x=-200, y=200),
        -math.sqrt(2.0 / math.pi) * (E - 1) / (2.0 * Hh),
        E / (2.0 * Hh),
        x=0,
        y=200,
    )
    # x = 1 + d / d_0; c = ln(1 + d_max / d_0) / (S - 1); s = ln x / c = log base e^c of x;
    # k0 = min(floor(s), S - 2) (x >= 1: s >= 0); w = (x e^(-c k0) - 1) / (e^c - 1), clamped
    # to [0, 1] (beyond d_max: w = 1, the last slice).
    inv_d0 = _math(group, "DIVIDE", 1.0, d0.outputs[0], x=-1200, y=-450)
    x = _math(group, "MULTIPLY_ADD", cam.outputs["View Distance"], inv_d0, 1.0, x=-1000, y=-300)
    c = _math(
        group,
        "DIVIDE",
        _math(
            group,
            "LOGARITHM",
            _math(group, "MULTIPLY_ADD", dmax.outputs[0], inv_d0, 1.0, x=-1000, y=-600),
            math.e,
            x=-800,
            y=-600,
        ),
        float(S - 1),
        x=-600,
        y=-600,
    )
    e_c = _math(group, "EXPONENT", c, x=-400, y=-600)
    s = _math(group, "LOGARITHM", x, e_c, x=-400, y=-300)
    k0 = _math(group, "MINIMUM", _math(group, "FLOOR", s, x=0, y=-300), float(S - 2), x=200, y=-300)
    inv_step = _math(group, "DIVIDE", 1.0, _math(group, "SUBTRACT", e_c, 1.0, x=-200, y=-750), x=0, y=-750)
    decay = _math(
        group,
        "EXPONENT",
        _math(group, "MULTIPLY", k0, _math(group, "MULTIPLY", c, -1.0, x=200, y=-600), x=400, y=-500),
        x=600,
        y=-500,
    )
    w = _math(
        group,
        "MULTIPLY_ADD",
        _math(group, "MULTIPLY", x, decay, x=700, y=-400),
        inv_step,
        _math(group, "MULTIPLY", inv_step, -1.0, x=700, y=-750),
        x=900,
        y=-400,
        clamp=True,
    )
    # v of the nearer slice's L texel; the others are + E / H (farther slice), + 1/2 (tau).
    v0 = _math(group, "MULTIPLY_ADD", k0, float(E) / Hh, rowh, x=600, y=0)
    return u, v0, w


def _closest_samples(group, u, v0):
    """The closest form's four bilinear samples around (u, v0): L and tau of both slices."""
    E, Hh = tab.ELEVATIONS, float(tab.HEIGHT)
    # The four texels around (u, v0) and the weights between them.
    Ww = float(tab.WIDTH)
    fx = _math(group, "MULTIPLY_ADD", u, Ww, -0.5, x=900, y=600)
    x0 = _math(group, "FLOOR", fx, x=1000, y=600)
    ax = _math(group, "SUBTRACT", fx, x0, x=1100, y=600)
    ua = _math(group, "DIVIDE", _math(group, "ADD", x0, 0.5, x=1100, y=700), Ww, x=1200, y=700)
    ub = _math(group, "ADD", ua, 1.0 / Ww, x=1300, y=700)
    fy = _math(group, "MULTIPLY_ADD", v0, Hh, -0.5, x=900, y=100)
    y0 = _math(group, "FLOOR", fy, x=1000, y=100)
    ay = _math(group, "SUBTRACT", fy, y0, x=1100, y=100)
    va = _math(group, "DIVIDE", _math(group, "ADD", y0, 0.5, x=1100, y=0), Hh, x=1200, y=0)

    def fetch_at(uu, vv, x, y):
        uv = group.nodes.new("ShaderNodeCombineXYZ")
        uv.location = (x, y)
        group.links.new(uu, uv.inputs[0])
        group.links.new(vv, uv.inputs[1])
        tex = group.nodes.new("ShaderNodeTexImage")
        tex.location = (x + 150, y)
        tex.image = table_image()
        tex.interpolation = "Closest"
        tex.extension = "REPEAT"
        group.links.new(uv.outputs[0], tex.inputs["Vector"])
        return tex.outputs["Color"]

    def lerp(p, q, t, x, y):  # p + (q - p) t
        return _vmath(
            group,
            "ADD",
            p,
            _vmath(group, "SCALE", _vmath(group, "SUBTRACT", q, p, x=x, y=y), scale=t, x=x + 100, y=y),
            x=x + 200,
            y=y,
        )

    samples = {}
    for n, offset in enumerate((0.0, E / Hh, 0.5, 0.5 + E / Hh)):
        y = 300 - 700 * n
        v_lo = _math(group, "ADD", va, offset, x=1300, y=y)
        v_hi = _math(group, "ADD", v_lo, 1.0 / Hh, x=1400, y=y)
        lo = lerp(fetch_at(ua, v_lo, 1500, y), fetch_at(ub, v_lo, 1500, y - 150), ax, 1800, y)
        hi = lerp(fetch_at(ua, v_hi, 1500, y - 300), fetch_at(ub, v_hi, 1500, y - 450), ax, 1800, y - 300)
        samples[n] = lerp(lo, hi, ay, 2100, y - 150)
    return samples


def _closest_outputs(group, samples, w):
    """The closest form's two AOVs: the slices mixed by w, and the opacity 1 - e^(-tau)."""

    def mix(near, far, x, y):  # near + (far - near) w: one Mix node
        node, a, b, out = compat.rgba_mix(group, "MIX")
        node.location = (x, y)
        group.links.new(w, node.inputs[0])
        group.links.new(near, a)
        group.links.new(far, b)
        return out

    L = mix(samples[0], samples[1], 2500, 300)
    tau = mix(samples[2], samples[3], 2500, -200)
    # 1 - T = 1 - e^(-tau) = 1 - (1/e)^tau, per channel.
    parts = group.nodes.new("ShaderNodeSeparateXYZ")
    parts.location = (2700, -200)
    group.links.new(tau, parts.inputs[0])
    transmit = group.nodes.new("ShaderNodeCombineXYZ")
    transmit.location = (3100, -200)
    for c in range(3):
        group.links.new(
            _math(group, "POWER", 1.0 / math.e, parts.outputs[c], x=2900, y=-100 - 150 * c),
            transmit.inputs[c],
        )
    opacity = _vmath(group, "SUBTRACT", (1.0, 1.0, 1.0), transmit.outputs[0], x=3300, y=-200)
    for name, socket, y in ((AOV_INSCATTER, L, 300), (AOV_OPACITY, opacity, -200)):
        aov = group.nodes.new("ShaderNodeOutputAOV")
        compat.set_aov_name(aov, name)
        aov.location = (3500, y)
        group.links.new(socket, aov.inputs["Color"])


def _closest_nodes(group):
    """The closest form (aerial_table.lookup() in nodes): coordinates, samples, AOVs."""
    u, v0, w = _closest_view(group)
    samples = _closest_samples(group, u, v0)
    _closest_outputs(group, samples, w)


def shader_group(fetch=None):
    """The node group that reads the table (aerial_table.screen_lookup() or lookup() in
    nodes), with its two AOV outputs, in the form `fetch` (None: the existing group's if it
    is the screen form, else FETCH_CLOSEST)."""
    group = bpy.data.node_groups.get(SHADER_GROUP)
    built = group.get(MARK) if group is not None else None
    if fetch is None:
        fetch = FETCH_SCREEN if built == _layout(FETCH_SCREEN) else FETCH_CLOSEST
    if built == _layout(fetch):
        return group
    if group is None:
        group = bpy.data.node_groups.new(SHADER_GROUP, "ShaderNodeTree")
    group.nodes.clear()
    if LATTICE in group:  # the constants went with the nodes
        del group[LATTICE]
    group[MARK] = _layout(fetch)
    if fetch == FETCH_SCREEN:
        _screen_nodes(group)
        return group
    _closest_nodes(group)
    return group


def _materials():
    return [m for m in bpy.data.materials if m.library is None and compat.material_uses_nodes(m)]


def install_materials():
    """Our node in every local material with nodes that lacks it; returns how many."""
    group = shader_group()
    added = 0
    for material in _materials():
        nodes = material.node_tree.nodes
        node = nodes.get(SHADER_NODE)
        if node is not None and node.get(MARK):
            continue
        node = nodes.new("ShaderNodeGroup")
        node.node_tree = group
        node.name = node.label = SHADER_NODE
        node[MARK] = True
        xs = [n.location.x for n in nodes if n is not node]
        node.location = (
            min(xs, default=0.0),
            max((n.location.y for n in nodes if n is not node), default=0.0) + 250.0,
        )
        added += 1
    return added


def remove_materials():
    for material in bpy.data.materials:
        if material.node_tree is None:
            continue
        for node in [n for n in material.node_tree.nodes if n.get(MARK) and n.name.startswith(SHADER_NODE)]:
            material.node_tree.nodes.remove(node)


# --- view layer AOVs ---------------------------------------------------------------------


def install_aovs(scene):
    """Adds our AOVs to every view layer; returns the names of the layers we added them to
    (as "layer\\tAOV" lines, for remove)."""
    added = []
    for layer in scene.view_layers:
        for name in AOVS:
            if any(a.name == name for a in layer.aovs):
                continue
            aov = layer.aovs.add()
            aov.name = name
            aov.type = "COLOR"
            added.append(f"{layer.name}\t{name}")
    return added


def remove_aovs(scene, added):
    for line in added:
        layer_name, name = line.split("\t")
        layer = scene.view_layers.get(layer_name)
        if layer is None:
            continue
        for index, aov in enumerate(layer.aovs):
            if aov.name == name:
                layer.active_aov_index = index
                with_context_remove_aov(scene, layer)
                break


def with_context_remove_aov(scene, layer):
    """ViewLayer AOVs have no remove() in the API: the operator removes the active one."""
    window = bpy.context.window
    override = {"scene": scene, "view_layer": layer}
    if window is not None:
        override["window"] = window
    with bpy.context.temp_override(**override):
        bpy.ops.scene.view_layer_remove_aov()


# --- the compositor ----------------------------------------------------------------------


def comp_group():
    group = bpy.data.node_groups.get(COMP_GROUP)
    if group is not None and group.get(MARK) == 2:
        return group
    if group is None:
        group = bpy.data.node_groups.new(COMP_GROUP, "CompositorNodeTree")
    else:  # an earlier version's group: rebuilt in place (its users keep their links)
        group.nodes.clear()
        compat.clear_group_sockets(group)
    group[MARK] = 2
    for name in ("Image", "Inscatter", "Opacity"):
        compat.new_group_socket(group, name, "INPUT", "NodeSocketColor")
    for name in ("Image", "Welkin.AerialInscatter", "Welkin.AerialTransmittance"):
        compat.new_group_socket(group, name, "OUTPUT", "NodeSocketColor")
    gin = group.nodes.new("NodeGroupInput")
    gin.location = (-500, 0)
    gout = group.nodes.new("NodeGroupOutput")
    gout.location = (500, 0)
    one_minus, white, opacity, t = compat.compositor_mix(group, "SUBTRACT")
    one_minus.location = (-250, -200)
    white.default_value = (1.0, 1.0, 1.0, 1.0)
    group.links.new(gin.outputs["Opacity"], opacity)
    mul, image, trans, dimmed = compat.compositor_mix(group, "MULTIPLY")
    mul.location = (0, 100)
    group.links.new(gin.outputs["Image"], image)
    group.links.new(t, trans)
    add, base, light, hazed = compat.compositor_mix(group, "ADD")
    add.location = (250, 100)
    group.links.new(dimmed, base)
    group.links.new(gin.outputs["Inscatter"], light)
    group.links.new(hazed, gout.inputs["Image"])
    group.links.new(gin.outputs["Inscatter"], gout.inputs["Welkin.AerialInscatter"])
    group.links.new(t, gout.inputs["Welkin.AerialTransmittance"])
    return group


def _render_layer_nodes(tree, scene):
    return [n for n in tree.nodes if n.bl_idname == "CompositorNodeRLayers" and n.scene in (None, scene)]


def install_compositor(scene, settings):
    """Our group after every Render Layers node of the scene (from 5.3 in our own
    compositor effect, compat.ensure_own_compositor); returns warnings."""
    warnings = []
    tree = compat.own_compositor(scene, CREATED_TREE)
    if tree is None or not settings.compositor_undo:
        tree, (kind, value) = compat.ensure_own_compositor(scene, CREATED_TREE)
        if not settings.compositor_undo:
            settings.compositor_undo = f"{kind}\t{value}"
    group = comp_group()
    for rl in _render_layer_nodes(tree, scene):
        if any(n.get(MARK) == rl.name for n in tree.nodes if n.bl_idname == "CompositorNodeGroup"):
            continue
        missing = [a for a in AOVS if a not in rl.outputs]
        if missing:
            warnings.append(f"the Render Layers node '{rl.name}' has no output {missing[0]}")
            continue
        _insert_haze(tree, rl, group)
    return warnings


def _insert_haze(tree, rl, group):
    """Our group node on the frame that comes from Render Layers `rl`, the frame's users
    (but KEEP_UNHAZED) moved to the group's output."""
    frame = compat.compositor_frame(tree, rl)
    node = tree.nodes.new("CompositorNodeGroup")
    node.node_tree = group
    node.name = node.label = COMP_NODE
    node[MARK] = rl.name
    node.location = (rl.location.x + 250, rl.location.y + 150)
    targets = [
        link.to_socket
        for link in tree.links
        if link.from_socket == frame and not link.to_node.get(MARK) and link.to_node.name not in KEEP_UNHAZED
    ]
    tree.links.new(frame, node.inputs["Image"])
    tree.links.new(rl.outputs[AOV_INSCATTER], node.inputs["Inscatter"])
    tree.links.new(rl.outputs[AOV_OPACITY], node.inputs["Opacity"])
    for socket in targets:
        tree.links.new(node.outputs["Image"], socket)


def remove_compositor(scene, settings):
    tree = compat.own_compositor(scene, CREATED_TREE)
    if tree is None and hasattr(scene, "node_tree"):
        tree = scene.node_tree
    if tree is not None:
        for node in [n for n in tree.nodes if n.bl_idname == "CompositorNodeGroup" and n.get(MARK)]:
            rl = tree.nodes.get(node[MARK])
            targets = [link.to_socket for link in tree.links if link.from_socket == node.outputs["Image"]]
            if rl is not None:
                frame = compat.compositor_frame(tree, rl)
                for socket in targets:
                    tree.links.new(frame, socket)
            tree.nodes.remove(node)
    if settings.compositor_undo:
        kind, value = settings.compositor_undo.split("\t", 1)
        compat.restore_scene_compositor(scene, kind, value, CREATED_TREE)
        settings.compositor_undo = ""


# --- all of it ---------------------------------------------------------------------------


def linked_material_warnings(scene):
    """One line per material of the scene's objects that comes from a library: its nodes
    are read-only, so our node cannot be added and its surfaces are not hazed."""
    linked = {}
    for ob in scene.objects:
        for slot in getattr(ob, "material_slots", ()):
            m = slot.material
            if m is not None and m.library is not None and m.node_tree is not None:
                linked[m.name_full] = m
    return [
        f"material '{m.name}' (on objects of this scene) is linked from the library "
        f"'{m.library.filepath}': its nodes cannot be changed, so aerial perspective cannot "
        f"add its node and surfaces with it are not hazed; make it local (Object > Relations "
        f"> Make Local) to haze them"
        for _name, m in sorted(linked.items())
    ]


def install(scene, settings):
    """Installs everything the frame's haze needs; returns warnings for the artist."""
    aovs = install_aovs(scene)
    if aovs:
        settings.added_aovs = "\n".join(filter(None, [settings.added_aovs, *aovs]))
    install_materials()
    return linked_material_warnings(scene) + list(install_compositor(scene, settings))


def remove(scene, settings):
    remove_compositor(scene, settings)
    remove_aovs(scene, [line for line in settings.added_aovs.split("\n") if line])
    settings.added_aovs = ""
    if not any(s.welkin_aerial.enabled for s in bpy.data.scenes if s != scene):
        remove_materials()
        for name in (SHADER_GROUP, COMP_GROUP):
            group = bpy.data.node_groups.get(name)
            if group is not None and group.get(MARK) and group.users == 0:
                bpy.data.node_groups.remove(group)
        for name in (IMAGE, *SCREEN_IMAGES, *OLD_IMAGES):
            image = bpy.data.images.get(name)
            if image is not None and image.get(MARK):
                bpy.data.images.remove(image)
