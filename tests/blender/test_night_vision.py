# SPDX-License-Identifier: Apache-2.0
"""Headless Blender: Night Vision (welkin.add_night_vision), the compositor group for the
dark-adapted eye (Jensen et al. 2001's scotopic tone mapping), against the formulas
computed here in numpy, independently of the add-on's code.

The frame: six flat emission strips seen by an orthographic camera (Cycles, one sample,
a pixel filter of 0.01 px, so that each strip's pixels hold its emission colour), at
luminances from photopic to scotopic, 200 to 2e-4 cd/m^2 (683 lm/W per unit of Y, the
sky's Exposure at 1). The user's compositing doubles the frame (a Multiply node between
the Render Layers and the output before 5.3; an effect of the user's from 5.3).

  * Without the group, the rendered frame is the physical one: twice the emission colours
    within 1e-5.
  * With it (acuity blur 3 px), each strip's interior (8 px from its edges) is the
    formulas of Jensen 2001 applied to the doubled colour within TOL (relative, of the
    pixel's largest channel): RGB -> XYZ by the sRGB matrix of IEC 61966-2-1 (four
    decimals, so TOL also covers its rounding against the add-on's matrix from the
    primaries), V = Y [1.33 (1 + (Y + Z) / X) - 1.68], s the smoothstep of log10(683 Y)
    over [-2, 0.6], chromaticity blended with (0.25, 0.25), luminance (1 - s) 0.4468 V +
    s Y. The photopic strip is unchanged within 1e-5 and the scotopic strips move by
    more than 30 % (the test can tell the group from no group).
  * The acuity blur acts where it is dark only: across the edge between the two scotopic
    strips the frame passes through values between the two strips' over 3 or more
    columns (none without the blur: the edge is sharp); the photopic strip's last column
    before its edge keeps its own value.
  * A stock Blender without the add-on renders the saved file (with the user's
    compositing and the group) to the same frame within 1e-6: the group is stock nodes.
  * The group's luminance scale is 683 / the sky's Exposure; a group of another version
    is rebuilt in place (the node keeps its links), a group of the user's with the same
    name is left alone; an output with nothing linked into it is refused with a report
    saying so, the compositing unchanged.
  * The user's nodes and links are unchanged after adding (the link into the output now
    runs through the group), and everything is as before after removing; the same for a
    scene with no compositing at all. The render after removing is the physical one again.
"""

import pathlib
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as at  # noqa: E402

addon, module = at.install_addon()
from welkin.blender import compat  # noqa: E402
from welkin.blender.sky import night_vision  # noqa: E402

EFFECTS = hasattr(bpy.types, "SceneCompositorEffect")  # Blender 5.3+
CREATED = "Welkin Night Vision Compositing"  # the add-on's effect (5.3+) or compositing group
STRIP_PX, H = 24, 16
GAIN = 2.0
BLUR_PX = 3.0
TOL = 1e-3
# (linear Rec.709 chromaticity, luminance in cd/m^2 of the doubled frame)
STRIPS = (
    ((0.8, 0.5, 0.3), 200.0),
    ((0.2, 0.4, 0.9), 2.0),
    ((0.8, 0.5, 0.3), 0.1),
    ((0.3, 0.8, 0.2), 0.03),
    ((0.2, 0.4, 0.9), 1e-3),
    ((0.8, 0.5, 0.3), 2e-4),
)
W = STRIP_PX * len(STRIPS)

# IEC 61966-2-1 (sRGB), linear RGB -> XYZ, D65.
SRGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])


def jensen(rgb, cd_per_unit=683.0):
    """Jensen et al. 2001's night vision of linear Rec.709 colours (N, 3), in their units."""
    X, Y, Z = (SRGB_TO_XYZ @ rgb.T).astype(np.float64)
    V = np.maximum(Y * (1.33 * (1.0 + (Y + Z) / X) - 1.68), 0.0)
    t = np.clip((np.log10(cd_per_unit * Y) + 2.0) / 2.6, 0.0, 1.0)
    s = 3.0 * t**2 - 2.0 * t**3
    x, y = X / (X + Y + Z), Y / (X + Y + Z)
    x2, y2 = (1 - s) * 0.25 + s * x, (1 - s) * 0.25 + s * y
    Y2 = (1 - s) * 0.4468 * V + s * Y
    xyz = np.stack([x2 * Y2 / y2, Y2, (1 - x2 - y2) * Y2 / y2])
    return (np.linalg.inv(SRGB_TO_XYZ) @ xyz).T, s


def strip_colours():
    """The emission colour of each strip (the frame before the user's x2)."""
    out = []
    for chroma, lum in STRIPS:
        c = np.array(chroma)
        out.append(c * (lum / 683.0) / (SRGB_TO_XYZ[1] @ c) / GAIN)
    return np.array(out)


def build_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    scene = bpy.context.scene
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    bg = compat.world_node_tree(scene.world).nodes.get("Background")
    if bg is not None:
        bg.inputs["Strength"].default_value = 0.0
    unit = 0.1  # world units per pixel
    for k, colour in enumerate(strip_colours()):
        bpy.ops.mesh.primitive_plane_add(
            size=1.0, location=((k + 0.5 - len(STRIPS) / 2) * STRIP_PX * unit, 0, 0)
        )
        plane = bpy.context.active_object
        plane.scale = (STRIP_PX * unit, 2 * H * unit, 1.0)
        mat = bpy.data.materials.new(f"Strip {k}")
        tree = compat.material_node_tree(mat)
        tree.nodes.clear()
        emit = tree.nodes.new("ShaderNodeEmission")
        emit.inputs["Color"].default_value = (*colour, 1.0)
        emit.inputs["Strength"].default_value = 1.0
        out = tree.nodes.new("ShaderNodeOutputMaterial")
        tree.links.new(emit.outputs[0], out.inputs["Surface"])
        plane.data.materials.append(mat)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location = (0.0, 0.0, 10.0)
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = W * unit
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 0
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = 0.01
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.render.resolution_percentage = 100
    compat.set_file_format(scene.render.image_settings, "OPEN_EXR")
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGB"
    scene.view_settings.view_transform = "Standard"
    return scene


def multiply(tree, source, gain):
    node, a, b, out = compat.compositor_mix(tree, "MULTIPLY")
    node.name = f"User x{gain:g}"
    b.default_value = (gain, gain, gain, 1.0)
    tree.links.new(source, a)
    return out


def user_compositing(scene):
    """The user's x2: an effect of their own (5.3+) or a node in the scene's compositor."""
    if EFFECTS:
        effect = scene.compositor_effects.new(name="User Grade")
        group = bpy.data.node_groups.new("User Grade Group", "CompositorNodeTree")
        compat.new_group_socket(group, "Image", "INPUT", "NodeSocketColor")
        compat.new_group_socket(group, "Image", "OUTPUT", "NodeSocketColor")
        gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
        group.links.new(multiply(group, gin.outputs["Image"], GAIN), gout.inputs["Image"])
        effect.node_group = group
        return
    tree, _undo = compat.ensure_scene_compositor(scene, "User Compositing")
    rl = next(n for n in tree.nodes if n.bl_idname == "CompositorNodeRLayers")
    target = compat.compositor_output(tree).inputs[0]
    tree.links.new(multiply(tree, rl.outputs["Image"], GAIN), target)


def tree_state(tree, skip=None):
    """Nodes (name, type, location, input values) and links of `tree`; with `skip` (our
    node's name), that node left out and the links through it joined."""
    nodes = sorted(
        (
            n.name,
            n.bl_idname,
            tuple(n.location),
            tuple(str(getattr(s, "default_value", None)) for s in n.inputs),
        )
        for n in tree.nodes
        if n.name != skip
    )
    links = []
    for link in tree.links:
        if link.to_node.name == skip:
            continue
        if link.from_node.name == skip:
            into = link.from_node.inputs[0].links[0]
            links.append(
                (
                    into.from_node.name,
                    into.from_socket.identifier,
                    link.to_node.name,
                    link.to_socket.identifier,
                )
            )
            continue
        links.append(
            (link.from_node.name, link.from_socket.identifier, link.to_node.name, link.to_socket.identifier)
        )
    return nodes, sorted(links)


def snapshot(scene, skip=None):
    """The user's compositing: the effects stack (5.3+; our effect left out with `skip`)
    or the scene's tree, and the file's node groups."""
    ours = (skip, CREATED) if skip else ()
    state = {"groups": sorted(g.name for g in bpy.data.node_groups if g.name not in ours)}
    if EFFECTS:
        effects = [e for e in scene.compositor_effects if e.name not in ours]
        state["effects"] = [
            (
                e.name,
                e.node_group.name if e.node_group else None,
                e.enable_for_render,
                tree_state(e.node_group),
            )
            for e in effects
        ]
        active = scene.compositor_effects.active
        state["active"] = active.name if active is not None and active.name not in ours else None
    else:
        tree = compat.scene_compositor(scene)
        state["tree"] = tree_state(tree, skip) if tree is not None else None
    return state


def render(scene, name):
    path = at.TMP / f"{name}.exr"
    at.render_still(scene, path)
    return at.read_rgb_exr(module, path).astype(np.float64)


def interiors(img):
    """Each strip's mean over its interior (8 px from its edges, 4 rows from the top and
    bottom), and the largest deviation from it there."""
    means, spread = [], 0.0
    for k in range(len(STRIPS)):
        block = img[4:-4, k * STRIP_PX + 8 : (k + 1) * STRIP_PX - 8]
        mean = block.reshape(-1, 3).mean(axis=0)
        spread = max(spread, float(np.abs(block - mean).max() / np.abs(mean).max()))
        means.append(mean)
    return np.array(means), spread


def check_physical(img, gain, label):
    got, spread = interiors(img)
    want = gain * strip_colours()
    rel = np.abs(got - want).max(axis=1) / want.max(axis=1)
    print(f"{label}: the frame vs the emission x{gain:g}: max {rel.max():.2e} (flat within {spread:.1e})")
    at.check(
        rel.max() < 1e-5 and spread < 1e-5, f"{label}: the frame is not the physical one ({rel.max():.2e})"
    )


def check_night(img, gain, label):
    got, spread = interiors(img)
    physical = gain * strip_colours()
    want, s = jensen(physical)
    rel = np.abs(got - want).max(axis=1) / np.abs(want).max(axis=1)
    moved = np.abs(got - physical).max(axis=1) / physical.max(axis=1)
    for k, (_chroma, lum) in enumerate(STRIPS):
        print(
            f"  {label} strip {k} ({lum:g} cd/m2, s {s[k]:.3f}): got {np.array2string(got[k], precision=5)} "
            f"want {np.array2string(want[k], precision=5)}: {rel[k]:.1e}; moved {moved[k]:.2f}"
        )
    at.check(rel.max() < TOL, f"{label}: the composite is {rel.max():.2e} from Jensen 2001's formulas")
    at.check(moved[0] < 1e-5, f"{label}: the photopic strip changed by {moved[0]:.2e}")
    at.check(moved[4:].min() > 0.3, f"{label}: the scotopic strips moved only {moved[4:].min():.2f}")
    at.check(spread < 1e-4, f"{label}: a strip's interior is not flat ({spread:.1e})")
    # The acuity blur: across the scotopic strips' edge (column 5 x 24), values between.
    row = img[H // 2]
    lo, hi = sorted((float(got[4].max()), float(got[5].max())))
    edge = row[5 * STRIP_PX - 6 : 5 * STRIP_PX + 6].max(axis=1)
    between = int(((edge > lo + 0.02 * (hi - lo)) & (edge < hi - 0.02 * (hi - lo))).sum())
    last_photopic = row[STRIP_PX - 1]
    sharp = float(np.abs(last_photopic - got[0]).max() / got[0].max())
    print(
        f"  {label}: {between} columns between the scotopic strips; photopic edge column off by {sharp:.1e}"
    )
    at.check(between >= 3, f"{label}: the scotopic edge is not blurred ({between} columns between)")
    at.check(sharp < 1e-4, f"{label}: the photopic strip is blurred at its edge ({sharp:.1e})")


def stock_render(scene, label):
    """The scene saved, rendered by a stock Blender without the add-on (-f 1)."""
    blend = at.TMP / f"{label}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    env, extra = at.command_line_blender(with_addon=False)
    out = at.TMP / f"{label}_stock_"
    command = [
        *at.blender_command(),
        "-b",
        "--factory-startup",
        str(blend),
        *extra,
        "-o",
        f"{out}#",
        "-f",
        "1",
    ]
    run = subprocess.run(command, env=env, capture_output=True, text=True, timeout=400)
    log = run.stdout + run.stderr
    at.check(run.returncode == 0, f"the stock render exited {run.returncode}:\n{log[-3000:]}")
    at.check(at.NO_WELKIN_SAYS in log, f"the stock Blender's check did not run:\n{log[-2000:]}")
    return at.read_rgb_exr(module, f"{out}1.exr").astype(np.float64)


def add_remove(scene, label, gain, stock=False):
    before = snapshot(scene)
    check_physical(render(scene, f"{label}_before"), gain, f"{label}, before")
    bpy.ops.welkin.add_night_vision(acuity_blur_px=BLUR_PX)
    node_name = "Welkin Night Vision"
    after_add = snapshot(scene, skip=node_name)
    for key in before:
        if key == "groups" or before[key] is None:  # the compositing add() turned on is its own
            continue
        at.check(
            before[key] == after_add[key],
            f"{label}: {key} changed by adding:\n{before[key]}\n{after_add[key]}",
        )
    if EFFECTS:
        names = [e.name for e in scene.compositor_effects]
        at.check(names[-1] == CREATED, f"{label}: the effects are {names}: night vision must be last")
    night = render(scene, f"{label}_night")
    check_night(night, gain, label)
    if stock:
        other = stock_render(scene, "stock")
        diff = float(np.abs(other - night).max() / np.abs(night).max())
        print(f"  {label}: a stock Blender without Welkin renders the same frame within {diff:.1e}")
        at.check(diff < 1e-6, f"{label}: the stock Blender's frame is {diff:.1e} off")
    bpy.ops.welkin.add_night_vision(acuity_blur_px=BLUR_PX)  # again: nothing more is added
    at.check(snapshot(scene, skip=node_name) == after_add, f"{label}: adding twice changed the compositing")
    bpy.ops.welkin.remove_night_vision()
    after = snapshot(scene)
    for key in before:
        at.check(
            before[key] == after[key], f"{label}: {key} changed by add + remove:\n{before[key]}\n{after[key]}"
        )
    at.check(node_name not in bpy.data.node_groups, f"{label}: the group is left behind")
    check_physical(render(scene, f"{label}_after"), gain, f"{label}, after removing")


def settings_and_bad_input(scene):
    """The group's luminance scale follows the sky's Exposure (683 / exposure); an output
    with nothing linked into it is refused with a report naming it, nothing changed."""
    users = bpy.data.node_groups.new("Welkin Night Vision", "CompositorNodeTree")  # the user's
    scene.world.welkin.exposure = 4.0
    bpy.ops.welkin.add_night_vision(acuity_blur_px=BLUR_PX)
    node = night_vision.night_node(scene)
    scale = node.node_tree.nodes["Luminance Scale"].outputs[0].default_value
    at.check(abs(scale - 683.0 / 4.0) < 1e-4, f"the luminance scale is {scale}, not 683 / 4")
    at.check(node.node_tree != users and len(users.nodes) == 0, "the user's group of that name was taken")
    # A group built by another version is rebuilt in place; the node keeps its links.
    node.node_tree["welkin_night_vision"] = "0/older"
    bpy.ops.welkin.add_night_vision(acuity_blur_px=BLUR_PX)
    node = night_vision.night_node(scene)
    at.check(node.node_tree.get("welkin_night_vision") != "0/older", "the older group was not rebuilt")
    at.check(
        bool(node.inputs[0].links) and bool(node.outputs[0].links), "the rebuilt group's node lost its links"
    )
    bpy.ops.welkin.remove_night_vision()
    at.check(bpy.data.node_groups.get("Welkin Night Vision") == users, "the user's group of that name went")
    bpy.data.node_groups.remove(users)
    scene.world.welkin.exposure = 1.0
    if EFFECTS:  # the add-on's own effect always links its input to its output
        return
    tree = compat.scene_compositor(scene)
    target = compat.compositor_output(tree).inputs[0]
    source = target.links[0].from_socket
    tree.links.remove(target.links[0])
    before = snapshot(scene)
    try:
        bpy.ops.welkin.add_night_vision(acuity_blur_px=BLUR_PX)
    except RuntimeError as error:
        print(f"an output with nothing linked: refused: {error}")
        at.check("nothing linked" in str(error), f"the report does not say what is wrong: {error}")
    else:
        raise AssertionError("an output with nothing linked into it was accepted")
    after = snapshot(scene)
    at.check(after == before, f"a refused add changed the compositing:\n{before}\n{after}")
    at.check("welkin_night_vision_undo" not in scene, "a refused add left its undo record")
    tree.links.new(source, target)


def main():
    scene = build_scene()
    add_remove(scene, "no compositing", 1.0)
    print("no compositing: the frame as Jensen 2001 maps it, restored exactly")
    user_compositing(scene)
    add_remove(scene, "user's x2", GAIN, stock=True)
    print("the user's compositing untouched, restored exactly")
    settings_and_bad_input(scene)
    at.done("test_night_vision")


main()
