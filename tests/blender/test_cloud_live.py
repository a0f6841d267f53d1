# SPDX-License-Identifier: Apache-2.0
"""A cloudy sky in the live UI is computed beside the interface (background.py).

Timers never fire in `blender -b`; as in test_addon_handlers.py this test stands in for the
UI: handlers._headless() returns False, and the test calls the timers' functions (the
debounce tick, then background.poll) itself. Checked:

  * turning the lamp arms the debounced tick; the tick starts a job and returns without
    the new sky (nothing is applied on the tick's call);
  * while the job runs, the status line shows its progress, and those status updates
    (depsgraph updates of the world) neither re-arm the tick nor cancel the job;
  * when poll() finds the job done, the world holds exactly the sky a synchronous Update
    Sky computes for the same state (same images to 1e-6 relative, same key);
  * a newer change replaces a running job: the old one is cancelled (its core run stopped
    by its progress callback, no result) and the world gets the newer state's sky;
  * cancel (and a frame change) stops a job: the world's images and key stay as they were.

Run: PYTHONPATH=build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cloud_live.py
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

scene, sun = t.new_scene(sun_elevation_deg=25.0, sun_azimuth_deg=30.0, resolution="512", camera_z=20.0)
world = scene.world
settings = world.welkin
settings.method = "lut"
c = world.welkin_clouds
c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 32, 4, 2, 2
ct.add_layer(world, bottom_altitude_m=900.0, top_altitude_m=1600.0, coverage=0.45, density_per_m=0.02)
bpy.ops.welkin.update_sky()
check("with clouds" in settings.status, settings.status)
key0 = settings.last_key


def tick_now():
    """The debounce delay passes and the tick runs (as Blender's timer would)."""
    check(H._state["armed"], "the change did not arm the tick")
    time.sleep(H.DEBOUNCE_S + 0.05)
    check(H._tick() is None, "the tick did not finish after the delay")


def wait_for_job():
    """Calls poll() as Blender's timer would until it is done; the status lines seen."""
    seen, start = [], time.monotonic()
    while B.poll() is not None:
        seen.append(settings.status)
        bpy.context.view_layer.update()  # the status change reaches depsgraph_update_post
        check(not H._state["armed"], "the job's own status update re-armed the tick")
        check(time.monotonic() - start < TIMEOUT_S, "the background sky never finished")
        time.sleep(0.05)
    return seen


def current_key():
    request, _lamp, _warnings = scene_sun.request_for(scene, settings, None)
    return update.sky_key(settings, request, update.clouds_of(scene))


def turn_lamp(elevation_deg):
    t.aim_sun(sun, elevation_deg, 30.0)
    bpy.context.view_layer.update()


# --- The lamp turns: a job, its progress, then exactly the synchronous sky.
turn_lamp(28.0)
tick_now()
job = B.current()
check(job is not None, "the tick started no background job for the cloudy sky")
check(settings.last_key == key0, "the tick applied the cloudy sky itself (the UI would wait)")
seen = wait_for_job()
check(job.result is not None and not job.cancelled, f"the job did not finish: {job.error}")
check(settings.last_key != key0, "the finished job's sky was not applied")
check(any(s.endswith(" %") for s in seen), f"no progress in the status line: {seen[:3]}")
live_sky = t.world_pixels(settings.sky_image).copy()
live_disc = [
    tuple(n.inputs[2].default_value)
    for n in scene.world.node_tree.nodes
    if n.get("welkin_role") == "disc_horner_0"
]
live_key = settings.last_key
check("with clouds" in settings.status, settings.status)
update.update_sky(scene, None, force=True, pack=False)
check(settings.last_key == live_key, "the synchronous update computed another state")
np.testing.assert_allclose(live_sky, t.world_pixels(settings.sky_image), rtol=1e-6, atol=0)
np.testing.assert_allclose(
    live_disc,
    [
        tuple(n.inputs[2].default_value)
        for n in scene.world.node_tree.nodes
        if n.get("welkin_role") == "disc_horner_0"
    ],
    rtol=1e-6,
)
check(np.isfinite(live_sky).all(), "the live cloudy sky is not finite")
print(
    f"live: lamp turned -> background job, {len(seen)} polls, progress shown, "
    f"= the synchronous sky ({settings.status})"
)

# --- A newer change replaces a running job (at 2048 a job runs for seconds).
settings.resolution = "2048"
bpy.context.view_layer.update()
tick_now()
first = B.current()
check(first is not None, "no job for the new resolution")
turn_lamp(31.0)
tick_now()
second = B.current()
check(second is not None and second is not first, "the newer change did not start a new job")
check(first.cancelled, "the older job was not cancelled")
first.thread.join(30.0)
check(not first.thread.is_alive() and first.result is None, "the cancelled job's core run did not stop")
B.cancel()
second.thread.join(30.0)
check(not second.thread.is_alive() and second.result is None, "cancel() did not stop the job")
check(B.poll() is None and settings.last_key == live_key, "a cancelled job changed the world's sky")
settings.resolution = "512"
bpy.context.view_layer.update()
tick_now()
wait_for_job()
check(settings.last_key == current_key(), "the world does not hold the newest state's sky")
print("live: a newer change cancels the running job; cancel() leaves the world's sky alone")

# --- A frame change cancels a running job (the frame's own update follows).
turn_lamp(34.0)
tick_now()
job = B.current()
H.on_frame_change_pre(scene)
check(job.cancelled and B.current() is None, "a frame change did not cancel the job")
job.thread.join(30.0)
check(not job.thread.is_alive(), "the job's thread did not end after the frame change")
print("live: a frame change cancels the background job")
t.done("test_cloud_live")
