# SPDX-License-Identifier: Apache-2.0
"""A VDB volume marked as a Welkin cloud is not baked into the world by default: Cycles and
EEVEE render the volume object itself, and a world that held it too would show it twice.
Volumes in World Sky (World.welkin_clouds.volumes_in_world) puts it there on request.

A ball of cloud (a real VDB file) 2.5 km ahead of the camera, marked, and no cloud layer:

  * default: Update Sky gives the clear sky: the world's sky image equals the one made
    with the volume unmarked, every pixel within 1e-6 relative, and the status does not
    say "with clouds"; the Welkin engine's scene (which has no other way to show the
    volume) still holds it;
  * Volumes in World Sky on: the sky image has the cloud: where the core's transmittance
    for that scene is below 0.9, over 90 % of the pixels differ from the clear sky by more
    than 1 %, and there are such pixels (over 20);
  * the switch is a world setting, saved with the file: off again, the clear sky returns
    within 1e-6.

Run: PYTHONPATH=$PWD/build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cloud_volume_world.py
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
from welkin.blender.engine import render_engine  # noqa: E402
from welkin.blender.sky import scene_sun, update  # noqa: E402

check = t.check
scene, sun = t.new_scene(sun_elevation_deg=25.0, sun_azimuth_deg=30.0, camera_z=2.0)
cam = scene.camera
cam.rotation_euler = (math.radians(95.0), 0.0, math.radians(-90.0))
cam.data.clip_end = 1e6
world = scene.world
c = ct.quick_cloudy_world(world)
paths = ct.write_vdb_sequence(t.TMP / "vdb", frames=(1,), size=16, voxel_m=60.0)
vol = ct.add_volume(scene, paths[0], location=(2500.0, 0.0, 450.0), sequence=0)
vol.welkin_cloud.density_scale = 0.02
check(not c.volumes_in_world, "Volumes in World Sky must be off by default")


def sky_after_update():
    bpy.ops.welkin.update_sky()
    return t.world_pixels(world.welkin.sky_image).copy(), world.welkin.status


def relative(a, ref):
    return np.abs(a - ref) / np.maximum(np.abs(ref), 1e-6 * float(np.abs(ref).mean()))


vol.welkin_cloud.enabled = False
clear, _ = sky_after_update()
vol.welkin_cloud.enabled = True
default, status = sky_after_update()
err = float(relative(default, clear).max())
print(f"default: world sky vs clear sky {err:.1e}; status: {status}")
check(err < 1e-6, f"the marked volume is in the world by default (sky differs by {err:.3g})")
check("with clouds" not in status, f"default status says clouds: {status}")
engine = json.loads(
    render_engine.scene_description_json(scene, bpy.context.evaluated_depsgraph_get(), native)
)
check(len(engine["clouds"]["volumes"]) == 1, "the Welkin engine's scene lost the volume")

c.volumes_in_world = True
cloudy, status = sky_after_update()
check("with clouds" in status, f"with Volumes in World Sky: {status}")
request, _lamp, _w = scene_sun.request_for(scene, world.welkin, None)
text = update.cloudy_scene_json(scene, world.welkin, request, update.clouds_of(scene), native)
_img, T = native.scene_sky_image(
    native.SceneDescription.from_json_string(text), 256, sun_disc=False, return_transmittance=True
)
cloud = T < 0.9
changed = float((relative(cloudy, clear).max(axis=-1)[cloud] > 0.01).mean())
print(f"Volumes in World Sky: {cloud.sum()} pixels with T < 0.9, {changed:.1%} of them changed by over 1 %")
check(cloud.sum() > 20, f"the volume covers {cloud.sum()} pixels of the world")
check(changed > 0.9, f"only {changed:.1%} of the volume's pixels changed")

c.volumes_in_world = False
again, status = sky_after_update()
err = float(relative(again, clear).max())
check(err < 1e-6 and "with clouds" not in status, f"switched off again: {err:.3g}, {status}")
t.done("test_cloud_volume_world")
