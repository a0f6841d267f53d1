# SPDX-License-Identifier: GPL-3.0-or-later
"""The add-on's nodes in the world's node tree.

The user's nodes are never changed: the add-on adds its own nodes in a frame, including
its own World Output, and makes that output the active one. The user's output (and
everything linked to it) stays as it was, one click away: remove() deletes the add-on's
nodes and makes the user's output active again, which restores the tree exactly.

The tree (energy appears once, docs/design.md):

    Environment Texture (sky, no disc) -> Background ---------------------------\
    the sun's disc from the view direction -> Background (strength = Is Camera Ray) -> Add -> World Output

The sun lamp lights the scene; the disc's Background has strength "Is Camera Ray", so
camera rays see the disc while diffuse, glossy and shadow rays, and Cycles' importance map
of the world, see the sky alone.

The disc is drawn analytically, so it is round and sharp at any focal length and world
resolution (sky_compute.DiscModel): with D the normalised view direction (Texture
Coordinate > Generated, the ray direction in a world shader in Cycles and EEVEE) and S the
direction of the disc's centre,
    sin rho = |D x S|   (exact in float32 at the sun's 0.27 degrees, where 1 - D.S is not),
    s = sin rho / sin alpha,  mu = sqrt(1 - s^2),
    L = sum_k c_k mu^k  (Horner, one Vector Math Multiply Add per power, RGB at once),
shown where s < 1, D.S > 0 and D.z is above the horizon. The numbers (S, alpha, the
horizon, c_k) are the nodes' input values, written at every update.

Cycles' world importance map: on "Automatic" it takes the resolution of the largest
environment texture, and building a 2048 x 1024 map took 4.3 s per render here (two
cores), against 0.4 s at 1024 x 512. The sky is smooth, so the add-on sets the map to
Manual, at most 1024 wide (the sky's width when smaller), and remove() puts the world's own
setting back.
"""

import math

from .. import compat

MAP_RESOLUTION = 1024
ROLE_KEY = "welkin_role"
# Roles of nodes older versions of the add-on made, deleted when the nodes are refreshed.
OLD_ROLES = ("disc_texture",)


def _ours(tree):
    return [n for n in tree.nodes if n.get(ROLE_KEY)]


def _node(tree, role, idname, location, parent):
    for n in tree.nodes:
        if n.get(ROLE_KEY) == role:
            return n
    n = tree.nodes.new(idname)
    n[ROLE_KEY] = role
    n.location = location
    n.parent = parent
    n.label = f"Welkin {role.replace('_', ' ')}"
    return n


def _active_outputs(tree):
    return [
        n
        for n in tree.nodes
        if n.bl_idname == "ShaderNodeOutputWorld" and n.is_active_output and not n.get(ROLE_KEY)
    ]


def _math(tree, role, operation, location, parent, *values, vector=False):
    n = _node(tree, role, "ShaderNodeVectorMath" if vector else "ShaderNodeMath", location, parent)
    n.operation = operation
    for socket, value in zip(n.inputs, values):
        if value is not None:
            socket.default_value = value
    return n


def _disc_nodes(tree, frame, x, y, disc):
    """The disc's radiance from the view direction (module docstring); returns the output
    socket of its colour. `disc`: a sky_compute.DiscModel, or None (nothing shown)."""
    links = tree.links
    degree = len(disc.coefficients) - 1 if disc is not None else 5
    coord = _node(tree, "disc_coordinate", "ShaderNodeTexCoord", (x, y), frame)
    view = _math(tree, "disc_view", "NORMALIZE", (x + 180, y), frame, vector=True)
    links.new(coord.outputs["Generated"], view.inputs[0])
    # sin rho = |D x S|, s = sin rho / sin alpha
    cross = _math(tree, "disc_cross", "CROSS_PRODUCT", (x + 360, y), frame, vector=True)
    sin_rho = _math(tree, "disc_sin_rho", "LENGTH", (x + 540, y), frame, vector=True)
    s = _math(tree, "disc_s", "DIVIDE", (x + 720, y), frame)
    s2 = _math(tree, "disc_s2", "MULTIPLY", (x + 900, y), frame)
    mu2 = _math(tree, "disc_mu2", "SUBTRACT", (x + 1080, y), frame, 1.0)
    mu2.use_clamp = True
    mu = _math(tree, "disc_mu", "SQRT", (x + 1260, y), frame)
    links.new(view.outputs["Vector"], cross.inputs[0])
    links.new(cross.outputs["Vector"], sin_rho.inputs[0])
    links.new(sin_rho.outputs["Value"], s.inputs[0])
    links.new(s.outputs["Value"], s2.inputs[0])
    links.new(s.outputs["Value"], s2.inputs[1])
    links.new(s2.outputs["Value"], mu2.inputs[1])
    links.new(mu2.outputs["Value"], mu.inputs[0])
    # Where the disc is: s < 1, in front (D.S > 0), above the horizon.
    inside = _math(tree, "disc_inside", "LESS_THAN", (x + 900, y - 200), frame, None, 1.0)
    dot = _math(tree, "disc_dot", "DOT_PRODUCT", (x + 360, y - 350), frame, vector=True)
    front = _math(tree, "disc_front", "GREATER_THAN", (x + 540, y - 350), frame, None, 0.0)
    view_z = _node(tree, "disc_view_z", "ShaderNodeSeparateXYZ", (x + 360, y - 500), frame)
    above = _math(tree, "disc_above", "GREATER_THAN", (x + 540, y - 500), frame)
    mask_a = _math(tree, "disc_mask_a", "MULTIPLY", (x + 1080, y - 250), frame)
    mask = _math(tree, "disc_mask", "MULTIPLY", (x + 1260, y - 250), frame)
    links.new(s.outputs["Value"], inside.inputs[0])
    links.new(view.outputs["Vector"], dot.inputs[0])
    links.new(dot.outputs["Value"], front.inputs[0])
    links.new(view.outputs["Vector"], view_z.inputs[0])
    links.new(view_z.outputs["Z"], above.inputs[0])
    links.new(inside.outputs["Value"], mask_a.inputs[0])
    links.new(front.outputs["Value"], mask_a.inputs[1])
    links.new(mask_a.outputs["Value"], mask.inputs[0])
    links.new(above.outputs["Value"], mask.inputs[1])
    # L = c_0 + mu (c_1 + mu (c_2 + ...)), one Multiply Add per power.
    horner = []
    for k in range(degree - 1, -1, -1):
        n = _math(
            tree,
            f"disc_horner_{k}",
            "MULTIPLY_ADD",
            (x + 1440 + 180 * (degree - 1 - k), y),
            frame,
            vector=True,
        )
        if horner:
            links.new(horner[-1].outputs["Vector"], n.inputs[0])
        links.new(mu.outputs["Value"], n.inputs[1])
        horner.append(n)
    radiance = _math(tree, "disc_radiance", "SCALE", (x + 1440 + 180 * degree, y), frame, vector=True)
    links.new(horner[-1].outputs["Vector"], radiance.inputs[0])
    links.new(mask.outputs["Value"], radiance.inputs["Scale"])
    # The numbers.
    if disc is not None:
        direction, sin_alpha = disc.direction, math.sin(disc.radius_rad)
        horizon, c = disc.horizon_z, disc.coefficients
    else:
        direction, sin_alpha, horizon = (0.0, 0.0, 1.0), 1.0, 2.0  # never above z = 2
        c = [(0.0, 0.0, 0.0)] * (degree + 1)
    cross.inputs[1].default_value = direction
    dot.inputs[1].default_value = direction
    s.inputs[1].default_value = sin_alpha
    above.inputs[1].default_value = horizon
    horner[0].inputs[0].default_value = tuple(float(v) for v in c[degree])
    for n, k in zip(horner, range(degree - 1, -1, -1)):
        n.inputs[2].default_value = tuple(float(v) for v in c[k])
    return radiance.outputs["Vector"]


def install(world, settings, sky_image, disc):
    """Adds (or refreshes) the add-on's nodes and makes its output active. `disc`: the
    sun's sky_compute.DiscModel, or None (no disc)."""
    if not settings.active:
        settings.previous_use_nodes = compat.world_uses_nodes(world)
    tree = compat.world_node_tree(world)
    cycles = getattr(world, "cycles", None)  # absent when Cycles is disabled
    if not _ours(tree):
        # The user's active outputs (one per render engine target at most).
        settings.previous_output = "\n".join(n.name for n in _active_outputs(tree))
        if cycles is not None:
            settings.previous_sampling = f"{cycles.sampling_method}:{cycles.sample_map_resolution}"
    # EEVEE Next (4.2+) would turn the sky's brightest texels into a sun light of its own,
    # beside the synced lamp: its extraction is turned off while the add-on's nodes are in.
    threshold = compat.world_sun_threshold(world)
    if threshold is not None and settings.previous_sun_threshold < 0.0:
        settings.previous_sun_threshold = threshold
    compat.set_world_sun_threshold(world, 0.0)
    if cycles is not None:
        cycles.sampling_method = "MANUAL"
        cycles.sample_map_resolution = min(MAP_RESOLUTION, sky_image.size[0])
    for n in _ours(tree):
        if n.get(ROLE_KEY) in OLD_ROLES:
            tree.nodes.remove(n)
    xs = [n.location.x for n in tree.nodes if not n.get(ROLE_KEY)] or [0.0]
    ys = [n.location.y for n in tree.nodes if not n.get(ROLE_KEY)] or [0.0]
    x0, y0 = min(xs), min(ys) - 400.0
    frame = _node(tree, "frame", "NodeFrame", (x0, y0), None)
    frame.label = "Welkin Sky"
    sky = _node(tree, "sky_texture", "ShaderNodeTexEnvironment", (x0, y0), frame)
    sky.image = sky_image
    sky.projection = "EQUIRECTANGULAR"
    sky.interpolation = "Linear"
    bg_sky = _node(tree, "sky_background", "ShaderNodeBackground", (x0 + 320, y0), frame)
    bg_sky.inputs["Strength"].default_value = 1.0
    disc_color = _disc_nodes(tree, frame, x0 - 1400, y0 - 350, disc)
    path = _node(tree, "light_path", "ShaderNodeLightPath", (x0 + 300, y0 - 650), frame)
    bg_disc = _node(tree, "disc_background", "ShaderNodeBackground", (x0 + 520, y0 - 350), frame)
    add = _node(tree, "add", "ShaderNodeAddShader", (x0 + 720, y0 - 100), frame)
    out = _node(tree, "output", "ShaderNodeOutputWorld", (x0 + 920, y0 - 100), frame)
    links = tree.links
    links.new(sky.outputs["Color"], bg_sky.inputs["Color"])
    links.new(disc_color, bg_disc.inputs["Color"])
    if settings.show_sun_disc and disc is not None:
        links.new(path.outputs["Is Camera Ray"], bg_disc.inputs["Strength"])
    else:
        for link in list(bg_disc.inputs["Strength"].links):
            links.remove(link)
        bg_disc.inputs["Strength"].default_value = 0.0
    links.new(bg_sky.outputs["Background"], add.inputs[0])
    links.new(bg_disc.outputs["Background"], add.inputs[1])
    links.new(add.outputs["Shader"], out.inputs["Surface"])
    out.target = "ALL"
    for n in tree.nodes:
        if n.bl_idname == "ShaderNodeOutputWorld" and n is not out:
            n.is_active_output = False
    out.is_active_output = True


def remove(world, settings):
    """Deletes the add-on's nodes; the user's output becomes active again."""
    tree = world.node_tree
    if tree is not None:
        for n in _ours(tree):
            tree.nodes.remove(n)
        for name in filter(None, settings.previous_output.split("\n")):
            previous = tree.nodes.get(name)
            if previous is not None:
                previous.is_active_output = True
    cycles = getattr(world, "cycles", None)
    if cycles is not None and settings.previous_sampling:
        method, resolution = settings.previous_sampling.split(":")
        cycles.sampling_method = method
        cycles.sample_map_resolution = int(resolution)
        settings.previous_sampling = ""
    if settings.previous_sun_threshold >= 0.0:
        compat.set_world_sun_threshold(world, settings.previous_sun_threshold)
        settings.previous_sun_threshold = -1.0
    compat.set_world_uses_nodes(world, settings.previous_use_nodes)
