"""The add-on's nodes in the world's node tree.

The user's nodes are never changed: the add-on adds its own nodes in a frame, including
its own World Output, and makes that output the active one. The user's output (and
everything linked to it) stays as it was, one click away: remove() deletes the add-on's
nodes and makes the user's output active again, which restores the tree exactly.

The tree (energy appears once, DESIGN.md):

    Environment Texture (sky, no disc) -> Background --------------------\
    Environment Texture (sun disc)     -> Background (strength = Is Camera Ray) -> Add -> World Output

The sun lamp lights the scene; the disc's Background has strength "Is Camera Ray", so
camera rays see the disc while diffuse, glossy and shadow rays, and Cycles' importance map
of the world, see the sky alone.

Cycles' world importance map: on "Automatic" it takes the resolution of the largest
environment texture, and building a 2048 x 1024 map took 4.3 s per render here (two
cores), against 0.4 s at 1024 x 512. Without the disc the sky is smooth, so the add-on
sets the map to Manual, at most 1024 wide (the sky's width when smaller), and remove()
puts the world's own setting back.
"""
from . import compat

MAP_RESOLUTION = 1024
ROLE_KEY = "welkin_role"


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
    return [n for n in tree.nodes if n.bl_idname == 'ShaderNodeOutputWorld'
            and n.is_active_output and not n.get(ROLE_KEY)]


def install(world, settings, sky_image, disc_image):
    """Adds (or refreshes) the add-on's nodes and makes its output active."""
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
        cycles.sampling_method = 'MANUAL'
        cycles.sample_map_resolution = min(MAP_RESOLUTION, sky_image.size[0])
    xs = [n.location.x for n in tree.nodes if not n.get(ROLE_KEY)] or [0.0]
    ys = [n.location.y for n in tree.nodes if not n.get(ROLE_KEY)] or [0.0]
    x0, y0 = min(xs), min(ys) - 400.0
    frame = _node(tree, "frame", 'NodeFrame', (x0, y0), None)
    frame.label = "Welkin Sky"
    sky = _node(tree, "sky_texture", 'ShaderNodeTexEnvironment', (x0, y0), frame)
    disc = _node(tree, "disc_texture", 'ShaderNodeTexEnvironment', (x0, y0 - 300), frame)
    path = _node(tree, "light_path", 'ShaderNodeLightPath', (x0 + 300, y0 - 550), frame)
    bg_sky = _node(tree, "sky_background", 'ShaderNodeBackground', (x0 + 320, y0), frame)
    bg_disc = _node(tree, "disc_background", 'ShaderNodeBackground', (x0 + 520, y0 - 300), frame)
    add = _node(tree, "add", 'ShaderNodeAddShader', (x0 + 720, y0 - 100), frame)
    out = _node(tree, "output", 'ShaderNodeOutputWorld', (x0 + 920, y0 - 100), frame)
    for tex, image in ((sky, sky_image), (disc, disc_image)):
        tex.image = image
        tex.projection = 'EQUIRECTANGULAR'
        tex.interpolation = 'Linear'
    bg_sky.inputs['Strength'].default_value = 1.0
    links = tree.links
    links.new(sky.outputs['Color'], bg_sky.inputs['Color'])
    links.new(disc.outputs['Color'], bg_disc.inputs['Color'])
    if settings.show_sun_disc:
        links.new(path.outputs['Is Camera Ray'], bg_disc.inputs['Strength'])
    else:
        for link in list(bg_disc.inputs['Strength'].links):
            links.remove(link)
        bg_disc.inputs['Strength'].default_value = 0.0
    links.new(bg_sky.outputs['Background'], add.inputs[0])
    links.new(bg_disc.outputs['Background'], add.inputs[1])
    links.new(add.outputs['Shader'], out.inputs['Surface'])
    out.target = 'ALL'
    for n in tree.nodes:
        if n.bl_idname == 'ShaderNodeOutputWorld' and n is not out:
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
