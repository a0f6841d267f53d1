# SPDX-License-Identifier: Apache-2.0
"""The sky follows the lamp in the UI: depsgraph_update_post arms one debounced timer,
which brings the sky up to date once the changes stop; a panel setting does the same;
save_pre packs what the live updates changed; the handlers survive loading a file.

Timers never fire in `blender -b`, and the handler ignores depsgraph updates there (a
headless script calls update_sky; renders get frame changes). So this test stands in for
the UI: it makes handlers._headless() return False and calls the timer's function itself
once its deadline has passed. Everything else is Blender's own machinery: the depsgraph
handler is called by Blender after view_layer.update()."""

import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender import handlers as H  # noqa: E402

H._headless = lambda: False
scene, sun = T.new_scene(30.0, 0.0, resolution="256")
bpy.ops.welkin.update_sky()
settings = scene.world.welkin
key0 = settings.last_key
T.check(not H._state["armed"], "armed before any change")

# Moving an unrelated object does not arm anything.
cube = bpy.data.objects.new("Cube", bpy.data.meshes.new("Cube"))
scene.collection.objects.link(cube)
bpy.context.view_layer.update()
cube.location.x = 3.0
bpy.context.view_layer.update()
T.check(not H._state["armed"], "moving an unrelated object armed the sky update")

# Drag the lamp: three depsgraph updates in a row arm one timer.
for elevation in (31.0, 33.0, 35.0):
    T.aim_sun(sun, elevation, 10.0)
    bpy.context.view_layer.update()
T.check(
    H._state["armed"] and bpy.app.timers.is_registered(H._tick),
    "rotating the lamp did not arm the update timer",
)
T.check(settings.last_key == key0, "the sky updated before the debounce delay")
T.check(H._tick() > 0.0, "the timer did not wait for the changes to stop")
T.check(settings.last_key == key0, "the sky updated before the debounce delay")
time.sleep(H.DEBOUNCE_S + 0.05)
T.check(H._tick() is None, "the timer did not finish after the delay")
T.check(not H._state["armed"], "still armed after the update")
s = tuple(sun.matrix_world.col[2][:3])
atm = welkin.Atmosphere.preset(welkin.Atmosphere.preset_names()[0])  # the add-on's default
sky = T.world_pixels(settings.sky_image)
np.testing.assert_allclose(sky, welkin.sky_image(atm, 0.0, s, 256, "auto", sun_disc=False), rtol=1e-6)
T.check(not H._stale(scene, None), "the sky is stale after the timer's update")
print("lamp rotation -> one debounced update with the new sun")

# Our own updates (lamp colour and strength) do not re-arm: no update loop.
bpy.context.view_layer.update()
T.check(not H._state["armed"], "the add-on's own lamp sync re-armed the timer")

# A panel setting arms it too.
settings.exposure = 0.5
T.check(H._state["armed"], "changing the exposure did not arm the update")
H._state["due"] = 0.0
H._tick()
np.testing.assert_allclose(
    T.world_pixels(settings.sky_image),
    welkin.sky_image(atm, 0.0, s, 256, "auto", sun_disc=False, exposure=0.5),
    rtol=1e-6,
)
print("a settings change -> an update")

# The live updates do not pack (that costs an EXR encode); save_pre does, so the file
# carries the sky it shows.
live = T.world_pixels(settings.sky_image).copy()
path = str(T.TMP / "live.blend")
bpy.ops.wm.save_as_mainfile(filepath=path)
bpy.ops.wm.open_mainfile(filepath=path)
scene = bpy.context.scene
np.testing.assert_allclose(T.world_pixels(scene.world.welkin.sky_image), live, rtol=1e-6)
for handlers, function in H._HANDLERS:
    T.check(function in handlers, f"{function.__name__} lost on file load")
print("save_pre packs the live sky; handlers persist across loading")

T.done("test_addon_handlers")
