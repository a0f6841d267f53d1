# SPDX-License-Identifier: Apache-2.0
"""Clouds in Blender, end to end (headless): a procedural layer and a marked VDB volume
(a 3-frame sequence written by the test with pyopenvdb).

  * World: Update Sky renders the world texture with the clouds; it is finite, equals
    the clear sky to 1e-5 relative where the clouds' transmittance is 1 (no cloud: the
    same sky method, composited with T = 1), and differs from it by more than 1 % on over
    90 % of the pixels whose transmittance is below 0.9; a live (timer) update does not
    recompute a cloudy sky.
  * Aerial (Cycles, 64 x 32): the passes EXR beside each frame holds Welkin.Clouds.RGBA
    and Welkin.CloudDepth.Z, finite, alpha in [0, 1], CloudDepth 1e10 where alpha is 0;
    the composited EXR equals Clouds.rgb + (1 - a)(Image T + Inscatter) to 1e-5 relative;
    the user's compositor node survives enable and disable.
  * A marked volume whose VDB file is missing: Update Sky fails with a report naming the
    object and the path, the aerial frame is reported and not written.
"""

import json
import math
import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

addon, native = t.install_addon()
from welkin import scene_export  # noqa: E402
from welkin.blender import compat  # noqa: E402
from welkin.blender.sky import update  # noqa: E402

check = t.check


def cloud_scene():
    scene, sun = t.new_scene(sun_elevation_deg=25.0, sun_azimuth_deg=30.0, camera_z=20.0)
    cam = scene.camera
    cam.rotation_euler = (math.radians(95.0), 0.0, math.radians(-90.0))  # +X, 5 deg up
    cam.data.clip_end = 1e6
    world = scene.world
    world.welkin.method = "lut"
    c = world.welkin_clouds
    c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 32, 4, 2, 2
    c.volumes_in_world = True  # the world texture holds the volume too
    ct.add_layer(world, bottom_altitude_m=900.0, top_altitude_m=1600.0, coverage=0.45, density_per_m=0.02)
    paths = ct.write_vdb_sequence(t.TMP / "vdb", frames=(1, 2, 3), value=1.0)
    vol = ct.add_volume(scene, paths[0], location=(2500.0, 0.0, 450.0))
    vol.welkin_cloud.density_scale = 0.01
    bpy.ops.mesh.primitive_plane_add(size=200000.0, location=(0.0, 0.0, 0.0))
    scene.frame_set(1)
    return scene, sun, vol, paths


scene, sun, vol, paths = cloud_scene()
world = scene.world

# --- World texture: clear, then cloudy.
vol.welkin_cloud.enabled = False
world.welkin_clouds.layers[0].enabled = False
bpy.ops.welkin.update_sky()
clear = t.world_pixels(world.welkin.sky_image).copy()
world.welkin_clouds.layers[0].enabled = True
vol.welkin_cloud.enabled = True
bpy.ops.welkin.update_sky()
check("with clouds" in world.welkin.status, world.welkin.status)
cloudy = t.world_pixels(world.welkin.sky_image).copy()
check(np.isfinite(cloudy).all(), "the cloudy world texture is not finite")
# Where the clouds are: their transmittance per pixel for the same scene (the core's).
from welkin.blender.sky import scene_sun  # noqa: E402

request, _lamp, _w = scene_sun.request_for(scene, world.welkin, None)
text = update.cloudy_scene_json(scene, world.welkin, request, update.clouds_of(scene), native)
_img, T = native.scene_sky_image(text, request.width, sun_disc=False, return_transmittance=True)
rel = (np.abs(cloudy - clear) / np.maximum(np.abs(clear), 1e-9)).max(axis=-1)
free, cloud = T > 1.0 - 1e-6, T < 0.9
check(
    free.sum() > 0.3 * T.size and cloud.sum() > 0.05 * T.size,
    f"the test wants clear and cloudy pixels: {free.mean():.2f} free, {cloud.mean():.2f} cloud",
)
check(rel[free].max() < 1e-5, f"where there is no cloud the sky changed: {rel[free].max()}")
frac = float((rel[cloud] > 0.01).mean())
print(
    f"world: {cloud.mean():.1%} of the sphere clouded (T < 0.9), {frac:.1%} of it changed "
    f"by over 1 %; cloud-free pixels unchanged to {rel[free].max():.1e} ({world.welkin.status})"
)
check(frac > 0.9, f"only {frac:.1%} of the clouded pixels changed")
# A live (timer) update leaves a cloudy sky alone and says why.
key = world.welkin.last_key
sun.rotation_quaternion.w += 0.01
bpy.context.view_layer.update()
update.update_sky(scene, None, live=True)
check(world.welkin.last_key == key and "Update Sky" in world.welkin.status, world.welkin.status)
t.aim_sun(sun, 25.0, 30.0)
bpy.context.view_layer.update()

# --- Aerial perspective with clouds (Cycles).
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 64, 32
scene.render.resolution_percentage = 100
compat.set_file_format(scene.render.image_settings, "OPEN_EXR")
scene.render.filepath = str(t.TMP / "out" / "frame_")
tree, _undo = compat.ensure_scene_compositor(scene, f"{scene.name} Compositing")
rl = next((n for n in tree.nodes if n.bl_idname == "CompositorNodeRLayers"), None)
comp = compat.compositor_output(tree)  # 5.0: the tree's Group Output
user = tree.nodes.new("CompositorNodeCurveRGB")  # (5.0 has no compositor Gamma node)
user.name = "User Curves"
tree.links.new(compat.compositor_frame(tree, rl), user.inputs["Image"])  # 5.3: Group Input
tree.links.new(user.outputs["Image"], comp.inputs["Image"])
names_before = {n.name for n in tree.nodes}
scene.welkin_aerial.side_files = True  # the pass files beside the render
scene.welkin_aerial.enabled = True
check(names_before <= {n.name for n in tree.nodes}, "enable removed a user node")
check(
    comp.inputs["Image"].links[0].from_node.name == "User Curves",
    "enable relinked the output away from the user's node",
)

scene.frame_set(1)
bpy.ops.render.render(write_still=True)
base = scene_export.file_base(bpy.path.abspath(scene.render.filepath))
passes_path = scene_export.frame_path(base, "aerial", 1)
check(pathlib.Path(passes_path).is_file(), f"no passes: {scene.welkin_aerial.status}")
pixels, names = native.read_exr(passes_path)
for name in scene_export.CLOUD_CHANNELS:
    check(name in names, f"{name} missing from the passes: {names}")


def chans(px, nm, wanted):
    return np.stack([px[..., nm.index(n)] for n in wanted], axis=-1)


clouds = chans(pixels, names, [f"Welkin.Clouds.{c}" for c in "RGBA"])
cdepth = pixels[..., names.index("Welkin.CloudDepth.Z")]
ins = chans(pixels, names, [f"Welkin.AerialInscatter.{c}" for c in "RGB"])
tr = chans(pixels, names, [f"Welkin.AerialTransmittance.{c}" for c in "RGB"])
check(np.isfinite(clouds).all() and np.isfinite(cdepth).all(), "cloud passes not finite")
a = clouds[..., 3]
check(((a >= 0) & (a <= 1)).all(), f"alpha outside [0, 1]: {a.min()} {a.max()}")
check((a > 0.05).mean() > 0.05, f"hardly any cloud in view: {(a > 0.05).mean():.3f}")
check((cdepth[a == 0] == 1e10).all(), "CloudDepth is not 1e10 where there is no cloud")
print(
    f"aerial: cloud cover {(a > 0.05).mean():.1%}, alpha max {a.max():.3f}, "
    f"cloud depth {cdepth[a > 0.05].min():.0f}..{cdepth[a > 0.05].max():.0f} m"
)
render = native.read_exr(scene_export.frame_path(base, "render", 1))
image = chans(render[0], render[1], [f"Image.{c}" for c in "RGB"])
composite = chans(*native.read_exr(scene_export.frame_path(base, "composite", 1)), "RGB")
expect = clouds[..., :3] + (1.0 - clouds[..., 3:]) * (image * tr + ins)
err = (np.abs(composite - expect) / np.maximum(np.abs(expect), 1e-6)).max()
check(err < 1e-5, f"composite != Clouds + (1 - a)(I T + S): {err}")
print(f"aerial: composite equation holds to {err:.2e}")
frame_json = json.loads(pathlib.Path(scene_export.frame_path(base, "scene", 1)).read_text())
check(frame_json["clouds"]["volumes"][0]["file"] == str(paths[0]), "frame 1's VDB file")

# --- A missing VDB: reported, nothing written.
vol.data.filepath = str(t.TMP / "vdb" / "gone.0001.vdb")
scene.frame_set(3)
try:
    bpy.ops.welkin.update_sky()
    raise AssertionError("a missing VDB must be refused")
except RuntimeError as error:
    check("'Cloud'" in str(error) and "gone.0003.vdb" in str(error), str(error))
t.render_still(scene, t.TMP / "out" / "frame_0003.exr")
status = scene.welkin_aerial.status
check("not written" in status and "gone.0003.vdb" in status, status)
check(
    not pathlib.Path(scene_export.frame_path(base, "aerial", 3)).exists(),
    "a passes file was written for a frame with a missing VDB",
)
print(f"missing VDB: {status}")
vol.data.filepath = str(paths[0])

scene.welkin_aerial.enabled = False
check({n.name for n in tree.nodes} == names_before, "disable did not restore the user's nodes")
check(comp.inputs["Image"].links[0].from_node.name == "User Curves", "user link not restored")
t.done("test_cloud_render")
