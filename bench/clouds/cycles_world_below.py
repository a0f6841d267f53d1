# SPDX-License-Identifier: Apache-2.0
"""Where Welkin's reference and Cycles part at a cloud's base: the light from below.

Welkin lights a cloud with the sun and the sky's mean radiance over the hemisphere above the
cloud's horizon and over the one below (include/welkin/clouds/illumination.hpp); Cycles
lights it with the add-on's world, whose lower hemisphere is the dim ground. This renders
one type's patch (bench/cycles_layer_patches.py, the "side" view) by Cycles under three
worlds, against the same reference and fast march:

* addon: the add-on's world as Update Sky makes it (bench/clouds/cycles_types_lighting.py's);
* below: the same, but every direction below the horizon gets the world's mean over the
  sphere (the sun disc left out): the light from below of an isotropic sky of the sphere's
  mean, what Welkin lit clouds with before the two hemispheres;
* uniform: the world's mean over the sphere in every direction, that isotropic sky light
  (up to the difference between the world's mean at the ground and the atmosphere's mean
  at the cloud).

The world's mean is measured by Cycles itself: an equirectangular camera at the scene
camera's place renders the world alone (the cloud hidden), and its pixels are averaged with
their solid angles, those the sun's disc lights left out.

    WELKIN_EXTENSION_ZIP=build/blender_dist/welkin-0.1.0-linux_x64.zip \
    build/venv-bpy-5.0/bin/python tests/blender/bpy_blender.py -b --factory-startup \
        --python-use-system-env --python bench/clouds/cycles_world_below.py -- \
        [--type stratus] [--size 72 48] [--samples 64] [--paths 96] [--voxel 40]
"""

import argparse
import atexit
import os
import pathlib
import shutil
import sys
import tempfile

import bpy
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import addon_testing as T  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
p = argparse.ArgumentParser()
p.add_argument("--type", default="stratus")
p.add_argument("--size", type=int, nargs=2, default=(72, 48))
p.add_argument("--samples", type=int, default=64, help="Cycles samples per seed")
p.add_argument("--bounces", type=int, default=256)
p.add_argument("--paths", type=int, default=96, help="reference paths per seed")
p.add_argument("--voxel", type=float, default=40.0)
args = p.parse_args(argv)

addon, native = T.install_addon()
import cycles_addon_clouds as ac  # noqa: E402
import cycles_layer_patches as lp  # noqa: E402
import cycles_volume as cv  # noqa: E402
from welkin.blender import compat  # noqa: E402  (the installed add-on's)

tmp = tempfile.mkdtemp(prefix="welkin_cycles_world_below_")
atexit.register(shutil.rmtree, tmp, ignore_errors=True)


def world_output(world):
    return next(
        n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeOutputWorld" and n.is_active_output
    )


def world_mean(scene):
    """The world's radiance averaged over the sphere (RGB), as Cycles renders it for camera
    rays, the sun's disc left out; and the means over the upper and lower halves."""
    cam_data = bpy.data.cameras.new("Pano")
    cam_data.type = "PANO"
    compat.camera_panorama(cam_data).panorama_type = "EQUIRECTANGULAR"
    pano = bpy.data.objects.new("Pano", cam_data)
    scene.collection.objects.link(pano)
    pano.location = scene.camera.location
    pano.rotation_euler = (np.pi / 2, 0.0, 0.0)  # looking along +Y, +Z up: rows are elevations
    saved = (
        scene.camera,
        scene.render.resolution_x,
        scene.render.resolution_y,
        scene.render.film_transparent,
    )
    hidden = [o for o in scene.objects if o.type == "VOLUME"]
    for o in hidden:
        o.hide_render = True
    scene.camera = pano
    scene.render.resolution_x, scene.render.resolution_y = 128, 64
    scene.render.film_transparent = False
    img = cv.render(scene, os.path.join(tmp, "world.exr"))[..., :3]
    scene.camera, scene.render.resolution_x, scene.render.resolution_y, scene.render.film_transparent = saved
    for o in hidden:
        o.hide_render = False
    bpy.data.objects.remove(pano)
    bpy.data.cameras.remove(cam_data)
    h = img.shape[0]
    # cv.render's rows: the first is the top of the frame (elevation +90 deg).
    el = (0.5 - (np.arange(h) + 0.5) / h) * np.pi
    w = np.cos(el)[:, None, None] * np.ones_like(img[..., :1])
    # The sun's disc (the add-on's camera-ray term): a pixel whose centre falls in it (the
    # scene's 0.01 px filter samples the centres) is a thousand times the sky's median
    # luminance and more (the disc is about a million times the sky; the brightest aureole
    # pixel of a 128 x 64 panorama a few tens); such pixels weigh nothing.
    lum = img @ ac.LUMINANCE
    disc_px = lum > 1000.0 * np.median(lum)
    w[disc_px] = 0.0
    state["disc_pixels"] = state.get("disc_pixels", []) + [int(disc_px.sum())]

    def mean(rows):
        return (img[rows] * w[rows]).sum(axis=(0, 1)) / w[rows].sum(axis=(0, 1))

    return mean(slice(None)), mean(el > 0), mean(el < 0)


def set_world(scene, variant, mean):
    """Puts the variant's world in front of the add-on's (its nodes stay; this is a scratch scene)."""
    if variant == "addon":
        return
    nt = scene.world.node_tree
    out = world_output(scene.world)
    src = out.inputs["Surface"].links[0].from_socket
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.inputs["Color"].default_value = (*[float(v) for v in mean], 1.0)
    bg.inputs["Strength"].default_value = 1.0
    if variant == "uniform":
        nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
        return
    coord = nt.nodes.new("ShaderNodeTexCoord")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    below = nt.nodes.new("ShaderNodeMath")
    below.operation = "LESS_THAN"
    below.inputs[1].default_value = 0.0
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(coord.outputs["Generated"], sep.inputs["Vector"])
    nt.links.new(sep.outputs["Z"], below.inputs[0])
    nt.links.new(below.outputs["Value"], mix.inputs["Fac"])
    nt.links.new(src, mix.inputs[1])
    nt.links.new(bg.outputs["Background"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])


patch = lp.write_patch(native, args.type, os.path.join(tmp, f"{args.type}.vdb"), args.voxel)
built = lp.build(T, native, patch, size=tuple(args.size), samples=args.samples, bounces=args.bounces)
scene, _sun = built
original_update = ac.update_sky
state = {}


def update_then_vary(scene, sun, native, lamp="ground", at=ac.CLOUD_AT):
    result = original_update(scene, sun, native, lamp=lamp, at=at)
    if "mean" not in state:
        state["mean"], state["up"], state["down"] = world_mean(scene)
    set_world(scene, state["variant"], state["mean"])
    if state["variant"] != "addon":  # what the variant's world is, measured as the original was
        m, up, down = world_mean(scene)
        print(
            f"{state['variant']}'s world, luminance: upper half {up @ ac.LUMINANCE:.4g}, "
            f"lower half {down @ ac.LUMINANCE:.4g} (the original's mean {state['mean'] @ ac.LUMINANCE:.4g})",
            flush=True,
        )
    return result


ac.update_sky = update_then_vary
rows = []
for variant in ("addon", "below", "uniform"):
    state["variant"] = variant
    r = lp.compare(T, native, patch, built, "side", paths=args.paths, tmp=tmp, log=lambda s: None)
    rows.append((variant, r))
    print(
        f"{variant}: "
        + "; ".join(
            f"{k} / Cycles "
            + ", ".join(f"{q} {r[k][q]:.3f} (+-{r[k + '_noise'][q]:.3f})" for q in lp.REGIONS)
            for k in ("fast", "reference")
        ),
        flush=True,
    )
lum = ac.LUMINANCE
print(
    f"{args.type}: the add-on's world at the camera, luminance: mean over the sphere {state['mean'] @ lum:.4g}, "
    f"upper half {state['up'] @ lum:.4g}, lower half (the ground) {state['down'] @ lum:.4g}; "
    f"disc pixels left out per measurement {state['disc_pixels']}"
)
print("| Cycles' world | fast: all | sunlit | shadow | base | reference: all | sunlit | shadow | base |")
print("|---|---|---|---|---|---|---|---|---|")
for variant, r in rows:
    print(
        f"| {variant} | "
        + " | ".join(
            f"{r[k][q]:.2f} ± {r[k + '_noise'][q]:.2f}" for k in ("fast", "reference") for q in lp.REGIONS
        )
        + " |"
    )
