# SPDX-License-Identifier: Apache-2.0
"""The scene JSON's "clouds" section from a Blender scene (docs/artists.md "Clouds in Blender"):
the world's procedural layers, a marked Volume object's VDB file for the current frame of
a real 3-frame sequence (the file Blender itself loads, Volume.grids.frame_filepath, in
each sequence mode), its matrix_world by rows in metres, grid and density scale; the
panel and the operators; bad input (a non-volume marked, a missing file) reported."""

import json
import pathlib
import sys

import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

addon, native = t.install_addon()
from welkin import cloud_export  # noqa: E402
from welkin.blender.clouds import scene as cloud_scene  # noqa: E402
from welkin.blender.sky.scene_sun import UserError  # noqa: E402

check = t.check
scene, sun = t.new_scene(sun_elevation_deg=20.0)
world = scene.world

# No clouds: no section (a clear sky's JSON is unchanged).
check(cloud_scene.clouds_section(scene) is None, "a clear sky has no clouds section")

# Operators: add a layer, the defaults are the core's.
bpy.ops.welkin.add_cloud_layer()
layers = world.welkin_clouds.layers
check(len(layers) == 1, "add_cloud_layer adds one layer")
defaults = native.CloudLayer()
for k in ("bottom_altitude_m", "top_altitude_m", "coverage"):
    check(
        abs(getattr(layers[0], k) - getattr(defaults, k)) < 1e-6,
        f"layer default {k} {getattr(layers[0], k)} != core {getattr(defaults, k)}",
    )
layers[0].coverage = 0.3
layers[0].wind_offset_m = (100.0, -50.0)
bpy.ops.welkin.add_cloud_layer()
bpy.ops.welkin.remove_cloud_layer()
check(len(layers) == 1, "remove_cloud_layer removes the active layer")
try:
    bpy.ops.welkin.remove_cloud_layer(index=5)
    raise AssertionError("a bad index must be refused")
except RuntimeError as error:
    check("index" in str(error), f"the report names the index: {error}")

# A 3-frame VDB sequence and a volume object showing it.
paths = ct.write_vdb_sequence(t.TMP / "vdb", frames=(1, 2, 3))
scene.unit_settings.scale_length = 1.0
vol_ob = ct.add_volume(scene, paths[0], location=(100.0, 200.0, 2500.0))
vol_ob.welkin_cloud.enabled = False
# Mark through the operator; a non-volume in the selection is refused, nothing marked.
for o in scene.objects:
    o.select_set(False)
vol_ob.select_set(True)
sun.select_set(True)
with bpy.context.temp_override(selected_objects=[vol_ob, sun]):
    try:
        bpy.ops.welkin.mark_cloud_volumes()
        raise AssertionError("marking a sun lamp must be refused")
    except RuntimeError as error:
        check("not a Volume" in str(error) and "Sun" in str(error), str(error))
    check(not vol_ob.welkin_cloud.enabled, "nothing is marked when the selection is bad")
with bpy.context.temp_override(selected_objects=[vol_ob]):
    bpy.ops.welkin.mark_cloud_volumes()
check(vol_ob.welkin_cloud.enabled, "mark_cloud_volumes marks the volume")
vol_ob.welkin_cloud.density_scale = 0.02

# The file for each frame is the one Blender loads, in every sequence mode.
vol = vol_ob.data
for mode, duration, offset in (
    ("CLIP", 3, 0),
    ("EXTEND", 3, 0),
    ("REPEAT", 3, 0),
    ("PING_PONG", 3, 0),
    ("REPEAT", 2, 1),
):
    vol.sequence_mode, vol.frame_duration, vol.frame_offset = mode, duration, offset
    for frame in range(-1, 8):
        scene.frame_set(frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        blender_path = vol_ob.evaluated_get(depsgraph).data.grids.frame_filepath
        ours = cloud_scene.volume_path(vol, frame)
        if blender_path:
            check(
                ours == bpy.path.abspath(blender_path),
                f"{mode} d={duration} o={offset} frame {frame}: ours {ours} != Blender's {blender_path}",
            )
        else:
            # Blender shows nothing (CLIP outside the range) or the file is absent.
            check(
                ours is None or not pathlib.Path(ours).exists(),
                f"{mode} frame {frame}: Blender loads nothing but we use {ours}",
            )
vol.sequence_mode, vol.frame_duration, vol.frame_offset = "CLIP", 3, 0

# The section at each frame: layer fields, the frame's file, matrix by rows, grid, scale.
texts = []
for frame in (1, 2, 3):
    scene.frame_set(frame)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    clouds = cloud_scene.clouds_section(scene, depsgraph)
    check(len(clouds["layers"]) == 1 and len(clouds["volumes"]) == 1, str(clouds))
    layer = clouds["layers"][0]
    check(abs(layer["coverage"] - 0.3) < 1e-6 and layer["wind_offset_m"] == [100.0, -50.0], str(layer))
    check(
        set(layer) == set(cloud_export.LAYER_FIELDS) | {"wind_offset_m", "seed"},
        f"layer keys {sorted(layer)}",
    )
    v = clouds["volumes"][0]
    check(v["file"] == str(paths[frame - 1]), f"frame {frame}: file {v['file']}")
    check(v["grid"] == "density" and abs(v["density_scale"] - 0.02) < 1e-9, str(v))
    check(
        v["matrix_world"][0][3] == 100.0
        and v["matrix_world"][2][3] == 2500.0
        and v["matrix_world"][3] == [0.0, 0.0, 0.0, 1.0],
        f"matrix by rows: {v['matrix_world']}",
    )
    check(
        clouds["lighting"]["max_steps"] == 96 and clouds["scattering"]["albedo"] == 1.0,
        str(clouds["lighting"]),
    )
    texts.append(json.dumps(clouds))
check(len(set(texts)) == 3, "each frame's section names its own file")

# The frame's scene JSON (the aerial handler's, validated by the core) carries the section.
from welkin.blender.aerial import scene as aerial  # noqa: E402

scene.frame_set(2)
text = aerial.scene_json(scene, native, bpy.context.evaluated_depsgraph_get())
desc = native.SceneDescription.from_json_string(text)
check(desc.has_clouds, "the core reads no clouds from the scene JSON")
exported = json.loads(text)["clouds"]
check(
    exported["volumes"][0]["file"] == str(paths[1])
    and abs(exported["layers"][0]["coverage"] - 0.3) < 1e-6
    and exported["volumes"][0]["matrix_world"][2][3] == 2500.0,
    str(exported),
)

# Outside a CLIP sequence's range the volume is left out (Blender hides it too).
scene.frame_set(5)
clouds = cloud_scene.clouds_section(scene, bpy.context.evaluated_depsgraph_get())
check(clouds["volumes"] == [], f"frame 5 is outside the CLIP range: {clouds['volumes']}")

# Scene units: the placement is written in metres.
scene.frame_set(1)
scene.unit_settings.scale_length = 0.5
clouds = cloud_scene.clouds_section(scene, bpy.context.evaluated_depsgraph_get())
m = clouds["volumes"][0]["matrix_world"]
check(abs(m[2][3] - 1250.0) < 1e-9 and abs(m[0][0] - 0.5) < 1e-12, f"scaled matrix {m}")
scene.unit_settings.scale_length = 1.0

# A missing file: a UserError naming the object and the path (nothing is written).
vol.filepath = str(t.TMP / "vdb" / "gone.0001.vdb")
try:
    cloud_scene.clouds_section(scene)
    raise AssertionError("a missing VDB must be refused")
except UserError as error:
    check("'Cloud'" in str(error) and "gone.0001.vdb" in str(error), str(error))
vol.filepath = str(paths[0])

# The panel draws the layer and lists the marked volume.
import types  # noqa: E402

log = []
layout = t.FakeLayout(log)
bpy.types.WORLD_PT_welkin_clouds.draw(
    types.SimpleNamespace(layout=layout), types.SimpleNamespace(world=world, scene=scene)
)
check(("prop", "coverage") in log and ("operator", "welkin.mark_cloud_volumes") in log, str(log))
check(
    any(k == "label" and "Cloud" in text for k, text in log if isinstance(text, str)),
    f"the marked volume is listed: {log}",
)
t.done("test_cloud_export")
