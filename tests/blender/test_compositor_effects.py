# SPDX-License-Identifier: Apache-2.0
"""Headless Blender: Aerial Perspective in the compositor beside the user's own compositing.

Blender 5.3 composites through a stack of effects (Scene.compositor_effects), each with
its own node group fed the frame of the effects before it; earlier versions have one
compositing tree. The user's compositing here brightens the frame twice (x2, then x3):
  * 5.3+: two effects of their own, made in one order and reordered (the second first),
    the first one active;
  * before: two Multiply nodes after the Render Layers in the scene's compositor.
With Aerial Perspective and Write Pass Files on, the rendered frame (F12) must be the
hazed frame brightened by the user's compositing, 6 (Image x T + Inscatter), with Image
and Depth the unhazed frame and Z pass that Welkin's File Output node wrote and T,
Inscatter from the core (welkin.aerial_perspective) for that depth: within 2 % over the
geometry beyond 1.5 km (blocks up to 24 km). Haze after the user's effects (6 Image x T + Inscatter) would be
some 10 % off there. Then, with it off again: the user's effects (names, groups, order,
active one, switches), their groups' nodes and links, and the file's node groups are
exactly as before, and no effect of Welkin's (nor an empty "Scene Effect") is left; the
same for a scene with no compositing at all. Reading the compositor on a depsgraph update
(Write Pass Files follows the output path) raises no DeprecationWarning from Welkin's
code (5.3 deprecates Scene.compositing_node_group).
"""

import json
import math
import pathlib
import sys
import warnings

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as at  # noqa: E402

addon, module = at.install_addon()
from welkin.blender import compat  # noqa: E402
from welkin.blender.aerial import compositor, frame as aerial_frame  # noqa: E402
from welkin.blender.aerial import handlers as aerial_handlers  # noqa: E402
from welkin.blender.aerial import scene as aerial  # noqa: E402

EFFECTS = hasattr(bpy.types, "SceneCompositorEffect")  # Blender 5.3+
W, H = 96, 48
GAIN = (2.0, 3.0)
TOL = 0.02


def multiply(tree, source, gain):
    """A Multiply node after `source` by a constant `gain`; returns its output."""
    node, a, b, out = compat.compositor_mix(tree, "MULTIPLY")
    node.name = f"User x{gain:g}"
    b.default_value = (gain, gain, gain, 1.0)
    tree.links.new(source, a)
    return out


def user_effect(scene, name, gain):
    """5.3+: an effect of the user's own that multiplies the frame by `gain`."""
    effect = scene.compositor_effects.new(name=name)
    group = bpy.data.node_groups.new(f"{name} Group", "CompositorNodeTree")
    compat.new_group_socket(group, "Image", "INPUT", "NodeSocketColor")
    compat.new_group_socket(group, "Image", "OUTPUT", "NodeSocketColor")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    group.links.new(multiply(group, gin.outputs["Image"], gain), gout.inputs["Image"])
    effect.node_group = group
    return effect


def user_compositing(scene):
    """The user's x2 then x3, as effects (5.3+) or in the one compositing tree."""
    if EFFECTS:
        user_effect(scene, "User Grade", GAIN[0])
        user_effect(scene, "User Boost", GAIN[1])
        bpy.ops.scene.move_compositor_effect_to_index(name="User Boost", index=0)
        scene.compositor_effects.active = scene.compositor_effects["User Grade"]
        return
    tree, _undo = compat.ensure_scene_compositor(scene, "User Compositing")
    rl = next(n for n in tree.nodes if n.bl_idname == "CompositorNodeRLayers")
    link = next(l for l in tree.links if l.from_node == rl and l.from_socket.name == "Image")
    target = link.to_socket
    tree.links.new(multiply(tree, multiply(tree, rl.outputs["Image"], GAIN[0]), GAIN[1]), target)


def tree_state(tree):
    nodes = sorted(
        (
            n.name,
            n.bl_idname,
            tuple(n.location),
            tuple(str(getattr(s, "default_value", None)) for s in n.inputs),
        )
        for n in tree.nodes
    )
    links = sorted(
        (l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
        for l in tree.links
    )
    return nodes, links


def snapshot(scene):
    """The user's compositing as a whole: the effects stack (5.3+) or the scene's tree."""
    state = {"groups": sorted(g.name for g in bpy.data.node_groups)}
    if EFFECTS:
        effects = scene.compositor_effects
        state["effects"] = [
            (
                e.name,
                e.node_group.name if e.node_group else None,
                e.enable_for_render,
                e.enable_for_preview,
                tree_state(e.node_group) if e.node_group else None,
            )
            for e in effects
        ]
        state["active"] = effects.active.name if effects.active is not None else None
    else:
        tree = compat.scene_compositor(scene)
        state["tree"] = tree_state(tree) if tree is not None else None
    return state


def build_scene():
    scene, sun = at.new_scene(sun_elevation_deg=8.0, sun_azimuth_deg=60.0, camera_z=30.0)
    sun.data.energy = 4.0
    cam = scene.camera
    cam.rotation_euler = (math.radians(88.5), 0.0, math.radians(-90.0))
    cam.data.lens = 30.0
    cam.data.clip_end = 1e6
    grey = bpy.data.materials.new("Grey")  # the haze is written by node materials
    if grey.node_tree is None:  # before 5.0 (use_nodes is deprecated from 5.0)
        grey.use_nodes = True
    bpy.ops.mesh.primitive_plane_add(size=200000.0)
    bpy.context.active_object.data.materials.append(grey)
    for k, d in enumerate((1500.0, 3000.0, 6000.0, 12000.0, 24000.0)):
        s = 0.15 * d
        bpy.ops.mesh.primitive_cube_add(size=s, location=(d, (k % 2 - 0.5) * 0.4 * d, 0.5 * s))
        bpy.context.active_object.data.materials.append(grey)
    scene.world.welkin.preset = "hazy"
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.render.resolution_percentage = 100
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.view_settings.view_transform = "Standard"
    for layer in scene.view_layers:
        layer.use_pass_z = True
    compat.set_exr(scene.render.image_settings, multilayer=False)
    scene.render.image_settings.color_depth = "32"
    return scene


def far_mask(z):
    """Pixels of geometry beyond 1.5 km whose neighbours within 2 pixels are within 10 %."""
    ok = np.isfinite(z) & (z > 1500.0) & (z < 1e9)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            n = np.roll(np.roll(z, dy, axis=0), dx, axis=1)
            ok &= np.abs(n - z) < 0.1 * z
    ok[:2, :] = ok[-2:, :] = ok[:, :2] = ok[:, -2:] = False
    return ok


def check_render(scene, tmp):
    """F12 with Write Pass Files: the frame is the user's x6 of the hazed frame."""
    scene.render.filepath = str(tmp / "f12.exr")
    bpy.ops.render.render(write_still=True)
    pixels, names = module.read_exr(str(tmp / "f12.exr"))
    got = np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)
    side = next(tmp.rglob("*welkin_render_0001.exr"))
    pixels, names = module.read_exr(str(side))

    def channel(part):  # the depth channel is Depth.V in 3.4, Depth.Z later
        return pixels[..., names.index(next(n for n in names if part in n))]

    image = np.stack([channel(f"Image.{c}") for c in "RGB"], axis=-1)
    z = channel("Depth.")
    d = json.loads(aerial.scene_json(scene, module))
    desc = module.SceneDescription.from_json_string(json.dumps(d))
    L, T = module.aerial_perspective(desc, np.ascontiguousarray(z))
    gain = GAIN[0] * GAIN[1]
    want, after = gain * (image * T + L), gain * image * T + L
    mask = far_mask(z)
    rel = np.abs(got - want)[mask] / np.maximum(want[mask], 1e-6)
    rel_after = np.abs(after - want)[mask] / np.maximum(want[mask], 1e-6)
    print(
        f"{mask.sum()} far pixels: F12 vs x6 (Image x T + Inscatter): max {rel.max():.4f} "
        f"mean {rel.mean():.5f}; haze after the user's x6 would be {rel_after.mean():.3f} off"
    )
    at.check(mask.sum() >= 30, f"only {mask.sum()} pixels beyond 1.5 km")
    at.check(rel.max() < TOL, f"the frame is {rel.max():.4f} from the user's x6 of the hazed frame")
    at.check(
        rel_after.mean() > 3 * TOL,
        f"the test cannot tell haze before from after the user's compositing ({rel_after.mean():.4f})",
    )


def welkin_left(scene):
    names = [g.name for g in bpy.data.node_groups if g.name.startswith("Welkin Compositing")]
    if EFFECTS:
        names += [e.name for e in scene.compositor_effects if e.name.startswith(("Welkin", "Scene Effect"))]
    return names


def check_no_deprecation(scene):
    """What runs on every depsgraph update with Write Pass Files on (the File Output node
    follows the output path), and a render's install, called here directly (a handler's
    exception is only printed): no DeprecationWarning from Welkin's code about the scene's
    compositor (Scene.compositing_node_group, Scene.use_nodes, Scene.node_tree)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        aerial_handlers.on_depsgraph_update(scene)
        at.check(compositor.depth_node(scene) is not None, "no File Output node")
        aerial_frame.install(scene, scene.welkin_aerial)
        scene.frame_set(1)
    ours = [
        f"{w.filename}:{w.lineno}: {w.message}"
        for w in caught
        if issubclass(w.category, DeprecationWarning)
        and "welkin" in w.filename
        and "'Scene." in str(w.message)
    ]  # the compositor's: the scene's properties
    at.check(not ours, "deprecated API used:\n" + "\n".join(ours))


def enable_disable(scene, tmp, render):
    before = snapshot(scene)
    scene.render.filepath = str(tmp / "side" / "out_")
    scene.welkin_aerial.side_files = True
    scene.welkin_aerial.enabled = True
    if EFFECTS:
        effects = scene.compositor_effects
        names = [e.name for e in effects]
        at.check(
            names == ["Welkin Compositing", *[e[0] for e in before["effects"]]],
            f"the effects are {names}: Welkin's first, then the user's in their order",
        )
        # (an empty stack's only effect is its active one: Blender has no "none active")
        want_active = before["active"] or "Welkin Compositing"
        at.check(
            effects.active.name == want_active,
            f"the active effect is {effects.active.name}, not {want_active}",
        )
    check_no_deprecation(scene)
    if render:
        check_render(scene, tmp)
    scene.welkin_aerial.enabled = False
    after = snapshot(scene)
    for key in before:
        at.check(
            before[key] == after[key], f"{key} changed by enable + disable:\n{before[key]}\n{after[key]}"
        )
    at.check(not welkin_left(scene), f"left behind: {welkin_left(scene)}")


def main():
    scene = build_scene()
    enable_disable(scene, at.TMP / "bare", render=False)
    print("no compositing: restored exactly, nothing of Welkin's left")
    user_compositing(scene)
    enable_disable(scene, at.TMP / "user", render=True)
    print(
        "the user's compositing "
        + ("effects" if EFFECTS else "tree")
        + " untouched, restored exactly, nothing of Welkin's left"
    )
    at.done("test_compositor_effects")


main()
