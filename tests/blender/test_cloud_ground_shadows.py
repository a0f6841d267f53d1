# SPDX-License-Identifier: Apache-2.0
"""Ground Shadows: the clouds' shadows fall on the ground in Cycles, through the add-on's
shadow layer, which is removed exactly.

A partly cloudy layer, the sun 50 degrees up; Ground Shadows on (extent 4 km, height
200 m, a 128 x 128 map), Shade Sun Lamp off (so that the lamp's strength is the clear
sun's and the shadows alone make the difference). A white ground plane lit by the sun lamp
alone (the world invisible to diffuse rays), seen from 1 km straight above by an
orthographic camera 3 km wide, 32 x 32:

  * the layer is there: an object of the add-on's, visible to shadow rays only;
  * each pixel's brightness with the layer, over its brightness with the layer hidden,
    is the clouds' transmittance towards the sun from that ground point (the core's
    welkin.cloud_transmittance, whose march is checked against Beer-Lambert in
    tests/cpp/test_cloud_shadow.cpp): median absolute difference below 0.02 and 95th
    percentile below 0.1 (the map's texels are 31 m, the pixels 94 m: the bilinear
    interpolation of the map against point values); and the ground is really shadowed in
    places (over 5 % of it below 0.7) and open in others (over 5 % above 0.95);
  * Ground Shadows off: Update Sky removes the object, its mesh, material and image:
    bpy.data's objects, meshes, materials and images are the ones from before (by name).

Run: PYTHONPATH=$PWD/build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cloud_ground_shadows.py
"""

import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

addon, native = t.install_addon()
from welkin.blender.clouds import shadows as cloud_shadows  # noqa: E402
from welkin.blender import compat  # noqa: E402
from welkin.blender.sky import scene_sun, update  # noqa: E402

check = t.check
N = 32
scene, sun = t.new_scene(sun_elevation_deg=50.0, sun_azimuth_deg=20.0, camera_z=1000.0)
world = scene.world
world.welkin.method = "lut"
world.welkin.resolution = "256"
c = world.welkin_clouds
c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 16, 2, 1, 1
ct.add_layer(
    world,
    bottom_altitude_m=1000.0,
    top_altitude_m=1600.0,
    coverage=0.4,
    density_per_m=0.02,
    base_scale_m=3000.0,
    weather_scale_m=6000.0,
)
bpy.ops.mesh.primitive_plane_add(size=8000.0, location=(0.0, 0.0, 0.0))
ground = bpy.context.active_object
material = bpy.data.materials.new("White")
nodes = compat.material_node_tree(material).nodes
nodes.remove(nodes["Principled BSDF"])
diffuse = nodes.new("ShaderNodeBsdfDiffuse")
diffuse.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
material.node_tree.links.new(diffuse.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])
ground.data.materials.append(material)
world.cycles_visibility.diffuse = False
world.cycles_visibility.glossy = False
cam = scene.camera
cam.rotation_euler = (0.0, 0.0, 0.0)
cam.data.type = "ORTHO"
cam.data.ortho_scale = 3000.0
cam.data.clip_end = 5000.0
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
scene.cycles.filter_width = 0.01
scene.render.resolution_x = scene.render.resolution_y = N
scene.render.resolution_percentage = 100
compat.set_file_format(scene.render.image_settings, "OPEN_EXR")
scene.render.image_settings.color_depth = "32"
scene.view_settings.view_transform = "Standard"

c.shadows = False
bpy.ops.welkin.update_sky()
before = {k: {i.name for i in getattr(bpy.data, k)} for k in ("objects", "meshes", "materials", "images")}
c.ground_shadows = True
c.shadow_extent_m, c.shadow_height_m, c.shadow_resolution = 4000.0, 200.0, 128
bpy.ops.welkin.update_sky()
layer = cloud_shadows.find(world)
check(layer is not None, "Ground Shadows made no shadow layer")
check(
    layer.visible_shadow
    and not any(getattr(layer, f"visible_{r}") for r in ("camera", "diffuse", "glossy", "transmission")),
    "the shadow layer must be visible to shadow rays only",
)


def shot(name):
    t.render_still(scene, t.TMP / name)
    return t.read_rgb_exr(native, t.TMP / name).mean(axis=-1)


lit = shot("shadowed.exr")
layer.hide_render = True
open_ground = shot("open.exr")
layer.hide_render = False
ratio = lit / np.maximum(open_ground, 1e-12)

# The core's transmittance from each pixel's ground point (pixel centres; top row +y).
centres = (np.arange(N) + 0.5) / N * 3000.0 - 1500.0
x, y = np.meshgrid(centres, centres[::-1], indexing="xy")
points = np.stack([x.ravel(), y.ravel(), np.zeros(N * N)], axis=-1)
request, _lamp, _w = scene_sun.request_for(scene, world.welkin, None)
text = update.shadow_scene_json(scene, world.welkin, request, update.clouds_of(scene), native)
T = np.asarray(native.cloud_transmittance(text, points)).reshape(N, N)
diff = np.abs(ratio - T)
print(
    f"ground shadows: |ratio - T| median {np.median(diff):.4f}, 95th percentile "
    f"{np.percentile(diff, 95):.4f}, max {diff.max():.4f}; shadowed (T < 0.7) "
    f"{(T < 0.7).mean():.1%}, open (T > 0.95) {(T > 0.95).mean():.1%}"
)
check(
    (T < 0.7).mean() > 0.05 and (T > 0.95).mean() > 0.05,
    f"the test wants shadowed and open ground: {(T < 0.7).mean():.2f}, {(T > 0.95).mean():.2f}",
)
check(
    np.median(diff) < 0.02 and np.percentile(diff, 95) < 0.1,
    f"the shadows on the ground are not the clouds' transmittance: median {np.median(diff):.3f}",
)

c.ground_shadows = False
bpy.ops.welkin.update_sky()
after = {k: {i.name for i in getattr(bpy.data, k)} for k in before}
check(after == before, f"Ground Shadows off left something: {after} vs {before}")
check(cloud_shadows.find(world) is None, "the shadow layer is still there")
t.done("test_cloud_ground_shadows")
