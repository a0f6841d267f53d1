"""The add-on's nodes in the scene's compositor; the user's nodes are never removed.

  * "Welkin Aerial Depth", a File Output node writing a multilayer EXR of the render's
    Image and Depth (Z pass) for every frame, <base>welkin_render_<frame>.exr: the only
    way to read the Z pass back in `blender -b` (the Viewer node cannot be read there).
  * "Welkin Aerial Perspective", a node group (Image x Transmittance + Inscatter, and the
    clouds over it: Clouds.rgb + (1 - Clouds.a) x that), placed
    between the Composite node and what fed it (the user's last node). Its Transmittance
    and Inscatter inputs are left unlinked, at 1 and 0, so the Composite node shows the
    render unchanged: Blender 3.4 composites a frame before render_post, where the passes
    are computed from the Z pass the File Output node wrote, so they cannot reach the same
    frame's Composite node (and feeding them a frame late would be silently wrong). The
    handler writes the hazed frame itself, <base>welkin_composite_<frame>.exr; to haze the
    Composite node of one frame in the UI, add Image nodes with that frame's passes EXR
    (layer Welkin, passes AerialTransmittance / AerialInscatter) and link them to the group.

Our nodes are found by name; remove() takes them out and puts back the link they replaced.
"""
import bpy

DEPTH_NODE = "Welkin Aerial Depth"
GROUP_NODE = "Welkin Aerial Perspective"
GROUP_NAME = "Welkin Aerial Perspective"
OURS = (DEPTH_NODE, GROUP_NODE)


def node_group():
    """The group (Image x Transmittance + Inscatter), then the clouds over it:
    Clouds.rgb + (1 - Clouds.a) x that (Welkin.Clouds is premultiplied and holds the air in
    front of the cloud: README "Clouds in Blender"). Made once per file; a group from an
    earlier version without the Clouds input is rebuilt in place (it is the add-on's own:
    the nodes that use it keep their links)."""
    group = bpy.data.node_groups.get(GROUP_NAME)
    if group is not None and "Clouds" in group.inputs:
        return group
    if group is None:
        group = bpy.data.node_groups.new(GROUP_NAME, 'CompositorNodeTree')
    for node in list(group.nodes):
        group.nodes.remove(node)
    gin = group.nodes.new('NodeGroupInput')
    gout = group.nodes.new('NodeGroupOutput')

    def socket(sockets, name, default=None):
        sock = sockets.get(name) or sockets.new('NodeSocketColor', name)
        if default is not None:
            sock.default_value = default
        return sock

    socket(group.inputs, "Image", (0.0, 0.0, 0.0, 1.0))
    socket(group.inputs, "Transmittance", (1.0, 1.0, 1.0, 1.0))  # no passes: pass through
    socket(group.inputs, "Inscatter", (0.0, 0.0, 0.0, 1.0))
    socket(group.inputs, "Clouds", (0.0, 0.0, 0.0, 0.0))  # transparent: no clouds
    socket(group.outputs, "Image")

    def mix(blend_type, x):
        node = group.nodes.new('CompositorNodeMixRGB')
        node.blend_type = blend_type
        node.use_clamp = False
        node.inputs[0].default_value = 1.0
        node.location = (x, 0)
        return node

    mul, add = mix('MULTIPLY', -150), mix('ADD', 50)
    split = group.nodes.new('CompositorNodeSepRGBA')
    split.location = (50, -250)
    one_minus = group.nodes.new('CompositorNodeMath')
    one_minus.operation = 'SUBTRACT'
    one_minus.use_clamp = False
    one_minus.inputs[0].default_value = 1.0
    one_minus.location = (250, -250)
    behind, over = mix('MULTIPLY', 250), mix('ADD', 450)
    links = group.links
    links.new(gin.outputs["Image"], mul.inputs[1])
    links.new(gin.outputs["Transmittance"], mul.inputs[2])
    links.new(mul.outputs[0], add.inputs[1])
    links.new(gin.outputs["Inscatter"], add.inputs[2])
    links.new(gin.outputs["Clouds"], split.inputs[0])
    links.new(split.outputs["A"], one_minus.inputs[1])
    links.new(add.outputs[0], behind.inputs[1])
    links.new(one_minus.outputs[0], behind.inputs[2])
    links.new(behind.outputs[0], over.inputs[1])
    links.new(gin.outputs["Clouds"], over.inputs[2])
    links.new(over.outputs[0], gout.inputs["Image"])
    gin.location = (-400, 0)
    gout.location = (650, 0)
    return group


def _render_layers(tree, scene):
    for node in tree.nodes:
        if node.bl_idname == 'CompositorNodeRLayers' and node.scene in (None, scene):
            return node
    node = tree.nodes.new('CompositorNodeRLayers')
    node.location = (-600, 0)
    return node


def _composite(tree):
    for node in tree.nodes:
        if node.bl_idname == 'CompositorNodeComposite':
            return node
    return None


def install(scene, settings, depth_base):
    """Adds (or updates) our nodes; returns a list of warnings."""
    warnings = []
    if not settings.nodes_installed:
        settings.previous_use_nodes = scene.use_nodes
    scene.use_nodes = True
    tree = scene.node_tree
    rl = _render_layers(tree, scene)
    out = tree.nodes.get(DEPTH_NODE)
    if out is None:
        out = tree.nodes.new('CompositorNodeOutputFile')
        out.name = out.label = DEPTH_NODE
        out.location = (rl.location.x + 300, rl.location.y - 350)
        out.file_slots.clear()
        out.file_slots.new("Image")
        out.file_slots.new("Depth")
    fmt = out.format
    fmt.file_format = 'OPEN_EXR_MULTILAYER'
    fmt.color_depth = '32'
    fmt.exr_codec = 'ZIP'
    out.base_path = depth_base
    tree.links.new(rl.outputs["Image"], out.inputs["Image"])
    if "Depth" in rl.outputs:
        tree.links.new(rl.outputs["Depth"], out.inputs["Depth"])
    else:
        warnings.append("the render layer has no Depth output: enable View Layer > Passes > Z")
    _install_group(scene, tree, rl, settings)
    settings.nodes_installed = True
    return warnings


def _install_group(scene, tree, rl, settings):
    if tree.nodes.get(GROUP_NODE) is not None:
        return
    comp = _composite(tree)
    if comp is None:
        comp = tree.nodes.new('CompositorNodeComposite')
        comp.location = (rl.location.x + 900, rl.location.y)
        tree.links.new(rl.outputs["Image"], comp.inputs["Image"])
    source = comp.inputs["Image"].links[0].from_socket if comp.inputs["Image"].is_linked else None
    group = tree.nodes.new('CompositorNodeGroup')
    group.node_tree = node_group()
    group.name = group.label = GROUP_NODE
    group.location = (comp.location.x - 250, comp.location.y)
    if source is not None:
        settings.previous_source = f"{source.node.name}\t{source.identifier}"
        tree.links.new(source, group.inputs["Image"])
    else:
        settings.previous_source = ""
    tree.links.new(group.outputs["Image"], comp.inputs["Image"])


def remove(scene, settings):
    """Takes our nodes out and relinks what fed the Composite node before."""
    tree = getattr(scene, "node_tree", None)  # (the pass files' nodes: before Blender 5.0)
    if tree is not None:
        group = tree.nodes.get(GROUP_NODE)
        comp = _composite(tree)
        if group is not None and comp is not None and settings.previous_source:
            name, identifier = settings.previous_source.split("\t")
            node = tree.nodes.get(name)
            socket = next((s for s in node.outputs if s.identifier == identifier), None) \
                if node is not None else None
            if socket is not None:
                tree.links.new(socket, comp.inputs["Image"])
        for name in OURS:
            node = tree.nodes.get(name)
            if node is not None:
                tree.nodes.remove(node)
    if settings.nodes_installed:
        scene.use_nodes = settings.previous_use_nodes
    settings.nodes_installed = False
    settings.previous_source = ""
