# SPDX-License-Identifier: Apache-2.0
"""The live UI shows a quick, low-resolution cloudy sky first and then refines it
(background.py).

As in test_cloud_live.py this test stands in for the UI (handlers._headless() returns
False; the test calls the timers' functions itself). A world of 1024 x 512 with a cloud
layer; the lamp turns; the tick starts a job; poll() is called as Blender's timer would:

  * while the job still runs, the world already shows the preview: a 256 x 128 sky image,
    equal (1e-6 relative) to the core's cloudy sky of the same scene at 256
    (welkin.scene_sky_image), the status saying "refining", the world's key not the full
    sky's (a preview is never a current sky) and the tick not re-armed by it;
  * then the full sky: 1024 x 512, equal (1e-6) to a synchronous Update Sky of the same
    state, and its key the current one;
  * a world of 256 gets no preview (nothing smaller to show first).

Run: PYTHONPATH=$PWD/build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cloud_preview.py
"""

import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, native = t.install_addon()
from welkin.blender.sky import background as B  # noqa: E402
from welkin.blender import handlers as H  # noqa: E402
from welkin.blender.sky import scene_sun, update  # noqa: E402

check = t.check
H._headless = lambda: False
TIMEOUT_S = 300.0

scene, sun = t.new_scene(sun_elevation_deg=25.0, sun_azimuth_deg=30.0, resolution="256", camera_z=20.0)
world = scene.world
settings = world.welkin
settings.method = "lut"
c = world.welkin_clouds
c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 24, 3, 1, 2
ct.add_layer(world, bottom_altitude_m=900.0, top_altitude_m=1600.0, coverage=0.5, density_per_m=0.02)
bpy.ops.welkin.update_sky()
settings.resolution = "1024"


def current_key():
    request, _lamp, _warnings = scene_sun.request_for(scene, settings, None)
    return update.sky_key(settings, request, update.clouds_of(scene))


def turn_lamp_and_tick(elevation_deg):
    t.aim_sun(sun, elevation_deg, 30.0)
    bpy.context.view_layer.update()
    check(H._state["armed"], "the change did not arm the tick")
    time.sleep(H.DEBOUNCE_S + 0.05)
    check(H._tick() is None, "the tick did not finish after the delay")
    job = B.current()
    check(job is not None, "the tick started no background job")
    return job


job = turn_lamp_and_tick(28.0)
previews, start = [], time.monotonic()
while B.poll() is not None:
    if not job.done.is_set() and job.preview_shown:
        image = settings.sky_image
        previews.append((tuple(image.size), t.world_pixels(image).copy(), settings.status, settings.last_key))
    bpy.context.view_layer.update()
    check(not H._state["armed"], "the preview re-armed the tick")
    check(time.monotonic() - start < TIMEOUT_S, "the background sky never finished")
    time.sleep(0.02)
check(job.result is not None, f"the job did not finish: {job.error}")
check(previews, "no preview was shown while the full sky was computed")
size, pixels, status, key = previews[0]
print(f"preview: {size}, '{status}', shown in {len(previews)} polls before the full sky")
check(size == (256, 128), f"the preview is {size}, not 256 x 128")
check("refining" in status, f"the status does not say refining: {status}")
check(key != current_key(), "the preview's key is the full sky's")
request, _lamp, _w = scene_sun.request_for(scene, settings, None)
text = update.cloudy_scene_json(scene, settings, request, update.clouds_of(scene), native)
ref = native.scene_sky_image(native.SceneDescription.from_json_string(text), 256, sun_disc=False)
err = float((np.abs(pixels - ref) / np.maximum(np.abs(ref), 1e-9)).max())
check(err < 1e-6, f"the preview differs from the core's 256-wide cloudy sky by {err:.3g}")

check(tuple(settings.sky_image.size) == (1024, 512), f"full sky {settings.sky_image.size[:]}")
check(settings.last_key == current_key(), "the full sky's key is not the current one")
live = t.world_pixels(settings.sky_image).copy()
update.update_sky(scene, None, force=True, pack=False)
np.testing.assert_allclose(live, t.world_pixels(settings.sky_image), rtol=1e-6, atol=0)
print(f"full: 1024 x 512 = the synchronous sky; preview = the core's 256 sky to {err:.1e}")

settings.resolution = "256"
bpy.context.view_layer.update()
job = turn_lamp_and_tick(31.0)
check(job.preview_request() is None, "a 256-wide world got a preview")
while B.poll() is not None:
    time.sleep(0.02)
check(job.preview is None and settings.last_key == current_key(), "256: no preview, current")
t.done("test_cloud_preview")
