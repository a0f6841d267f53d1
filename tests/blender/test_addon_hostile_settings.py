# SPDX-License-Identifier: Apache-2.0
"""Headless Blender: settings and scenes a careful user (or a script) makes that the add-on
must handle, each the way Blender's own tools would.

(a) Cloud layers added from Python with `layers.add()` are what Update Sky computes (not
    the previous layers of the world's evaluated copy); more than the core's 32 enabled
    layers are refused with a report naming the limit, and the sky on screen stays as it
    was (not "FINISHED with clouds").
(b) A layer's wind offset or evolution that is NaN is refused naming the setting and
    "finite" (not the JSON parser's "invalid literal" at some byte); the wind offset's
    property holds at most 1e9 m (the core's range), as the evolution's.
(c) Aerial perspective with Blender's default camera (Clip End 100 m) hazes the frame: the
    table is baked for 100 m, no error in the status.
(d) A material linked from a library (its nodes cannot be changed) is reported by name
    when aerial perspective is turned on: its surfaces are not hazed, and the artist is
    told which material and why.
(e) A frame whose haze cannot be made (no sun lamp) fails `blender -b file --addons welkin
    -f 1`: a console line naming the frame and why, and (the Blender binary) a non-zero
    exit with no image written.
"""

import math
import os
import pathlib
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender.aerial import frame as aerial_frame  # noqa: E402
from welkin.blender import compat  # noqa: E402


def update_sky_error():
    """The ERROR report of Update Sky, or None when it finished."""
    try:
        bpy.ops.welkin.update_sky()
    except RuntimeError as error:
        return str(error)
    return None


scene, sun = T.new_scene(30.0, 40.0, resolution="256")
world = scene.world
world.welkin.method = "lut"
c = world.welkin_clouds
c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 16, 2, 1, 1

# (a) Layers from Python.
c.layers.add()  # a cumulus layer, the default
T.check(update_sky_error() is None, world.welkin.status)
T.check('"cirrus"' not in world.welkin.last_key, "a cirrus layer before one was added")
second = c.layers.add()
second.name = "High"
second.cloud_type = "cirrus"
second.bottom_altitude_m, second.top_altitude_m = 8000.0, 9000.0
T.check(update_sky_error() is None, world.welkin.status)
T.check(
    '"cirrus"' in world.welkin.last_key,
    f"Update Sky ignored the layer added with layers.add(): {world.welkin.last_key[-400:]}",
)
key, status = world.welkin.last_key, world.welkin.status
for _ in range(1000):
    c.layers.add()
error = update_sky_error()
T.check(
    error is not None and "1002 enabled cloud layers" in error and "at most 32" in error,
    f"Update Sky with 1002 layers: {error!r}, status {world.welkin.status!r}",
)
T.check(
    world.welkin.last_key == key and world.welkin.status == status,
    "the refused update changed the sky on screen",
)
while len(c.layers) > 2:
    c.layers.remove(len(c.layers) - 1)
second = c.layers[1]  # the collection grew: earlier references to its items are stale
T.check(update_sky_error() is None, world.welkin.status)
print("(a) layers added from Python are computed; 1002 are refused naming the limit of 32")

# (b) NaN and the property's range.
for name in ("wind_offset_m", "evolution_m"):
    if name == "wind_offset_m":
        second.wind_offset_m = (math.nan, 0.0)
    else:
        second.evolution_m = math.nan
    error = update_sky_error()
    field = "wind_offset_m[0]" if name == "wind_offset_m" else name
    T.check(
        error is not None
        and "'High'" in error
        and f"{field}: must be a finite number" in error
        and "JSON" not in error,
        f"NaN {name}: {error!r}",
    )
    second.wind_offset_m, second.evolution_m = (0.0, 0.0), 0.0
second.wind_offset_m = (1e20, -math.inf)
T.check(tuple(second.wind_offset_m) == (1e9, -1e9), f"wind offset held {tuple(second.wind_offset_m)}")
second.evolution_m = 1e300
T.check(second.evolution_m == 1e9, f"evolution held {second.evolution_m}")
second.wind_offset_m, second.evolution_m = (0.0, 0.0), 0.0
bpy.ops.welkin.remove_sky()
c.layers.clear()
print("(b) NaN wind or evolution is named; the properties hold the core's range")

# (c) Blender's default camera: Clip End 100 m.
cam = scene.camera
cam.data.clip_end = 100.0  # the startup file's camera (a new camera's data has 1000 m)
cam.location = (0.0, 0.0, 2.0)
cam.rotation_euler = (math.radians(85.0), 0.0, 0.0)
scene.render.engine = compat.eevee_engine_id()  # the direction table (Cycles reads another)
scene.render.resolution_x, scene.render.resolution_y = 32, 16
scene.welkin_aerial.enabled = True
status = scene.welkin_aerial.status
T.check("max_distance" not in status and "must be" not in status, f"status: {status!r}")
group = aerial_frame.shader_group(aerial_frame.FETCH_CLOSEST)
d_max = group.nodes[aerial_frame.MAX_DISTANCE_NODE].outputs[0].default_value
T.check(abs(d_max - 100.0) < 1e-3, f"the table was baked for {d_max} m, not the camera's 100 m")
print(f"(c) a camera that sees 100 m is hazed ({scene.render.engine}), status {status!r}")

# (d) A material linked from a library.
lib_path = T.TMP / "library.blend"
lib_material = bpy.data.materials.new("LibraryMarble")
lib_material.use_nodes = True
bpy.data.libraries.write(str(lib_path), {lib_material})
bpy.data.materials.remove(lib_material)
with bpy.data.libraries.load(str(lib_path), link=True) as (data_from, data_to):
    data_to.materials = ["LibraryMarble"]
linked = data_to.materials[0]
T.check(linked.library is not None, "the material was not linked")
mesh = bpy.data.meshes.new("Plane")
mesh.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0)], [], [(0, 1, 2)])
mesh.materials.append(linked)
plane = bpy.data.objects.new("Plane", mesh)
scene.collection.objects.link(plane)
scene.welkin_aerial.enabled = False
scene.welkin_aerial.enabled = True
warnings = aerial_frame.linked_material_warnings(scene)
T.check(
    len(warnings) == 1
    and "LibraryMarble" in warnings[0]
    and "linked" in warnings[0]
    and str(lib_path) in warnings[0]
    and "not hazed" in warnings[0],
    f"warnings: {warnings}",
)
T.check("LibraryMarble" in scene.welkin_aerial.status, f"status: {scene.welkin_aerial.status!r}")
T.check(linked.node_tree.nodes.get(aerial_frame.SHADER_NODE) is None, "the linked material changed")
bpy.data.objects.remove(plane)
scene.welkin_aerial.enabled = False
print("(d) a linked material is reported by name:", warnings[0][:80], "...")

# (e) A frame whose haze cannot be made, in a command-line render.
bpy.data.objects.remove(sun)
scene.render.image_settings.file_format = "PNG"
out = T.TMP / "e"
scene.render.filepath = str(out / "f_####")
scene.welkin_aerial.enabled = True
blend = T.TMP / "nosun.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
env["BLENDER_USER_SCRIPTS"] = str(T.scripts_dir())
env["BLENDER_USER_CONFIG"] = str(T.TMP / "config")
command = [*T.blender_command(), "-b", "--factory-startup", str(blend), "--addons", "welkin", "-f", "1"]
run = subprocess.run(command, env=env, capture_output=True, text=True, timeout=400)
log = run.stdout + run.stderr
T.check(
    "aerial perspective not written for frame 1" in log and "sun" in log,
    f"no console line for the failed frame:\n{log[-3000:]}",
)
if not T.is_module_bpy():  # the bpy module cannot stop a render (farm.py): said, not stopped
    T.check(run.returncode != 0, f"the -f 1 render exited {run.returncode}:\n{log[-3000:]}")
    T.check(not list(pathlib.Path(out).glob("f_*.png")), "an image was written for the failed frame")
print(f"(e) a frame without haze: exit {run.returncode}, the console says why")

T.done("test_addon_hostile_settings")
