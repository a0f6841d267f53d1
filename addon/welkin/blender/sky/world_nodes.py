# SPDX-License-Identifier: GPL-3.0-or-later
"""The add-on's nodes in the world's node tree.

The user's nodes are never changed: the add-on adds its own nodes in a frame, including
its own World Output, and makes that output the active one. The user's output (and
everything linked to it) stays as it was, one click away: remove() deletes the add-on's
nodes and makes the user's output active again, which restores the tree exactly.

The tree (energy appears once, docs/design.md):

    Environment Texture (sky, no disc) -> Background ---------------------------\
    the sun's disc from the view direction -> Background (strength = Is Camera Ray) -> Add -\
    the moon's disc from the view direction -> Background (strength = Is Camera Ray) -> Add -> World Output

The sun lamp (and the moon lamp, Place and Time) lights the scene; the discs' Backgrounds
have strength "Is Camera Ray", so camera rays see the discs while diffuse, glossy and
shadow rays, and Cycles' importance map of the world, see the sky alone.

The disc is drawn analytically, so it is round and sharp at any focal length and world
resolution (sky_compute.DiscModel): with D the normalised view direction (Texture
Coordinate > Generated, the ray direction in a world shader in Cycles and EEVEE) and S the
direction of the disc's centre,
    sin rho = |D x S|   (exact in float32 at the sun's 0.27 degrees, where 1 - D.S is not),
    s = sin rho / sin alpha,  mu = sqrt(1 - s^2),
    L = sum_k c_k mu^k  (Horner, one Vector Math Multiply Add per power, RGB at once),
shown where s < 1, D.S > 0 and D.z is above the horizon. The numbers (S, alpha, the
horizon, c_k) are the nodes' input values, written at every update.

The moon's disc (sky_compute.MoonDiscModel) with its phase: with M its centre and P the
direction from the moon towards the sun, s and mu as above, and
    mu0 = (D x M) . W - mu (M . P),   W = (P x M) / sin alpha   (a constant),
L = K mu0 / (mu0 + mu) where mu0 > 0 (the lit side: the terminator is mu0 = 0), s < 1,
D.M > 0 and above the horizon: the Lommel-Seeliger law seen from afar, K the RGB scale that
makes its integral the moon's irradiance. The nodes always exist (zero when there is no
moon), so that a farm bake keys the same nodes on every frame.

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


def _disc_radius_nodes(tree, prefix, frame, x, y, view):
    """A disc's radial coordinate from the normalised view direction D (`view`): the nodes
    <prefix>_cross (D x C, C the centre, linked by the caller), <prefix>_sin_rho,
    <prefix>_s = sin rho / sin alpha (the divisor linked by the caller) and <prefix>_mu =
    sqrt(1 - s^2), clamped; returns (cross, s, mu)."""
    links = tree.links
    cross = _math(tree, f"{prefix}_cross", "CROSS_PRODUCT", (x, y), frame, vector=True)
    sin_rho = _math(tree, f"{prefix}_sin_rho", "LENGTH", (x + 180, y), frame, vector=True)
    s = _math(tree, f"{prefix}_s", "DIVIDE", (x + 360, y), frame)
    s2 = _math(tree, f"{prefix}_s2", "MULTIPLY", (x + 540, y), frame)
    mu2 = _math(tree, f"{prefix}_mu2", "SUBTRACT", (x + 720, y), frame, 1.0)
    mu2.use_clamp = True
    mu = _math(tree, f"{prefix}_mu", "SQRT", (x + 900, y), frame)
    links.new(view.outputs["Vector"], cross.inputs[0])
    links.new(cross.outputs["Vector"], sin_rho.inputs[0])
    links.new(sin_rho.outputs["Value"], s.inputs[0])
    links.new(s.outputs["Value"], s2.inputs[0])
    links.new(s.outputs["Value"], s2.inputs[1])
    links.new(s2.outputs["Value"], mu2.inputs[1])
    links.new(mu2.outputs["Value"], mu.inputs[0])
    return cross, s, mu


def _disc_nodes(tree, frame, x, y, disc):
    """The disc's radiance from the view direction (module docstring); returns the output
    socket of its colour. `disc`: a sky_compute.DiscModel, or None (nothing shown)."""
    links = tree.links
    degree = len(disc.coefficients) - 1 if disc is not None else 5
    coord = _node(tree, "disc_coordinate", "ShaderNodeTexCoord", (x, y), frame)
    view = _math(tree, "disc_view", "NORMALIZE", (x + 180, y), frame, vector=True)
    links.new(coord.outputs["Generated"], view.inputs[0])
    # sin rho = |D x S|, s = sin rho / sin alpha
    cross, s, mu = _disc_radius_nodes(tree, "disc", frame, x + 360, y, view)
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


def _moon_disc_nodes(tree, frame, x, y, view, view_z, moon):
    """The moon's disc with its phase from the view direction (module docstring); returns
    the output socket of its colour. `view`, `view_z`: the sun disc's normalised view
    direction and its Separate XYZ. `moon`: a sky_compute.MoonDiscModel, or None."""
    links = tree.links
    cross, s, mu = _disc_radius_nodes(tree, "moon", frame, x, y, view)
    # mu0 = (D x M) . W - mu (M . P), on the lit side only; L = mu0 / (mu0 + mu).
    lit = _math(tree, "moon_w", "DOT_PRODUCT", (x + 180, y - 180), frame, vector=True)
    mu0 = _math(tree, "moon_mu0", "MULTIPLY_ADD", (x + 1080, y - 180), frame)
    mu0_lit = _math(tree, "moon_mu0_lit", "MAXIMUM", (x + 1260, y - 180), frame, None, 0.0)
    total = _math(tree, "moon_mu0_mu", "ADD", (x + 1440, y - 180), frame)
    law = _math(tree, "moon_law", "DIVIDE", (x + 1620, y - 180), frame)  # 0 / 0 gives 0
    links.new(cross.outputs["Vector"], lit.inputs[0])
    links.new(mu.outputs["Value"], mu0.inputs[0])
    links.new(lit.outputs["Value"], mu0.inputs[2])
    links.new(mu0.outputs["Value"], mu0_lit.inputs[0])
    links.new(mu0_lit.outputs["Value"], total.inputs[0])
    links.new(mu.outputs["Value"], total.inputs[1])
    links.new(mu0_lit.outputs["Value"], law.inputs[0])
    links.new(total.outputs["Value"], law.inputs[1])
    # Where the disc is: s < 1, in front (D.M > 0), above the horizon.
    inside = _math(tree, "moon_inside", "LESS_THAN", (x + 540, y - 360), frame, None, 1.0)
    dot = _math(tree, "moon_dot", "DOT_PRODUCT", (x, y - 540), frame, vector=True)
    front = _math(tree, "moon_front", "GREATER_THAN", (x + 180, y - 540), frame, None, 0.0)
    above = _math(tree, "moon_above", "GREATER_THAN", (x + 180, y - 720), frame)
    mask_a = _math(tree, "moon_mask_a", "MULTIPLY", (x + 720, y - 450), frame)
    mask = _math(tree, "moon_mask", "MULTIPLY", (x + 900, y - 450), frame)
    shown = _math(tree, "moon_shown", "MULTIPLY", (x + 1800, y - 270), frame)
    links.new(s.outputs["Value"], inside.inputs[0])
    links.new(view.outputs["Vector"], dot.inputs[0])
    links.new(dot.outputs["Value"], front.inputs[0])
    links.new(view_z.outputs["Z"], above.inputs[0])
    links.new(inside.outputs["Value"], mask_a.inputs[0])
    links.new(front.outputs["Value"], mask_a.inputs[1])
    links.new(mask_a.outputs["Value"], mask.inputs[0])
    links.new(above.outputs["Value"], mask.inputs[1])
    links.new(law.outputs["Value"], shown.inputs[0])
    links.new(mask.outputs["Value"], shown.inputs[1])
    radiance = _math(tree, "moon_radiance", "SCALE", (x + 1980, y - 270), frame, vector=True)
    links.new(shown.outputs["Value"], radiance.inputs["Scale"])
    # The numbers.
    if moon is not None:
        m = tuple(float(c) for c in moon.direction)
        p = tuple(float(c) for c in moon.sun_from_moon)
        sin_alpha = math.sin(moon.radius_rad)
        w = (
            (p[1] * m[2] - p[2] * m[1]) / sin_alpha,
            (p[2] * m[0] - p[0] * m[2]) / sin_alpha,
            (p[0] * m[1] - p[1] * m[0]) / sin_alpha,
        )
        m_dot_p = m[0] * p[0] + m[1] * p[1] + m[2] * p[2]
        horizon, scale = moon.horizon_z, tuple(float(c) for c in moon.scale_rgb)
    else:
        m, w, m_dot_p, sin_alpha, horizon = (0.0, 0.0, 1.0), (0.0, 0.0, 0.0), 0.0, 1.0, 2.0
        scale = (0.0, 0.0, 0.0)
    cross.inputs[1].default_value = m
    dot.inputs[1].default_value = m
    lit.inputs[1].default_value = w
    mu0.inputs[1].default_value = -m_dot_p
    s.inputs[1].default_value = sin_alpha
    above.inputs[1].default_value = horizon
    radiance.inputs[0].default_value = scale
    return radiance.outputs["Vector"]


def install(world, settings, sky_image, disc, moon_disc=None):
    """Adds (or refreshes) the add-on's nodes and makes its output active. `disc`: the
    sun's sky_compute.DiscModel, or None (no disc); `moon_disc`: the moon's
    sky_compute.MoonDiscModel, or None (no moon disc)."""
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
    moon_color = _moon_disc_nodes(
        tree,
        frame,
        x0 - 2000,
        y0 - 1000,
        _node(tree, "disc_view", "ShaderNodeVectorMath", (0, 0), frame),  # made by _disc_nodes
        _node(tree, "disc_view_z", "ShaderNodeSeparateXYZ", (0, 0), frame),
        moon_disc,
    )
    path = _node(tree, "light_path", "ShaderNodeLightPath", (x0 + 300, y0 - 650), frame)
    bg_disc = _node(tree, "disc_background", "ShaderNodeBackground", (x0 + 520, y0 - 350), frame)
    bg_moon = _node(tree, "moon_background", "ShaderNodeBackground", (x0 + 520, y0 - 900), frame)
    add = _node(tree, "add", "ShaderNodeAddShader", (x0 + 720, y0 - 100), frame)
    add_moon = _node(tree, "moon_add", "ShaderNodeAddShader", (x0 + 900, y0 - 300), frame)
    out = _node(tree, "output", "ShaderNodeOutputWorld", (x0 + 1100, y0 - 100), frame)
    links = tree.links
    links.new(sky.outputs["Color"], bg_sky.inputs["Color"])
    links.new(disc_color, bg_disc.inputs["Color"])
    links.new(moon_color, bg_moon.inputs["Color"])
    for bg, model in ((bg_disc, disc), (bg_moon, moon_disc)):
        if settings.show_sun_disc and model is not None:
            links.new(path.outputs["Is Camera Ray"], bg.inputs["Strength"])
        else:
            for link in list(bg.inputs["Strength"].links):
                links.remove(link)
            bg.inputs["Strength"].default_value = 0.0
    links.new(bg_sky.outputs["Background"], add.inputs[0])
    links.new(bg_disc.outputs["Background"], add.inputs[1])
    links.new(add.outputs["Shader"], add_moon.inputs[0])
    links.new(bg_moon.outputs["Background"], add_moon.inputs[1])
    links.new(add_moon.outputs["Shader"], out.inputs["Surface"])
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
