# SPDX-License-Identifier: Apache-2.0
"""The cloud layer panel's Coverage Measure (docs/artists.md "Cloud types"): what a layer's
coverage means, the sky dome a ground observer sees covered (oktas / 8, "dome", the
default, as the core's) or the ground's area under cloud ("area"). The panel offers it, the
scene JSON carries it, the core reads it, and the layer built from the frame's scene is
calibrated to that measure: the share the core measures in it is the setting, for each."""

import json
import pathlib
import sys
import types

import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402

addon, native = t.install_addon()
from welkin import cloud_export  # noqa: E402
from welkin.blender.aerial import scene as aerial_scene  # noqa: E402
from welkin.blender.clouds import scene as cloud_scene  # noqa: E402

check = t.check
scene, sun = t.new_scene(sun_elevation_deg=30.0)
world = scene.world

bpy.ops.welkin.add_cloud_layer()
layer = world.welkin_clouds.layers[0]

# The default is the core's, and every item is a measure the core knows.
check(layer.coverage_measure == "dome", f"default {layer.coverage_measure}")
check(native.CloudLayer().coverage_measure == "dome", "the core's default is dome")
items = {i.identifier for i in layer.bl_rna.properties["coverage_measure"].enum_items}
check(items == set(cloud_export.COVERAGE_MEASURES), f"items {items}")
for m in sorted(items):
    check(native.CloudLayer(coverage=0.0, coverage_measure=m).coverage_measure == m, m)
try:
    layer.coverage_measure = "oktas"
    raise AssertionError("an unknown measure must be refused")
except TypeError as error:
    check("oktas" in str(error), str(error))

# The panel offers it, beside the coverage.
log = []
bpy.types.WORLD_PT_welkin_clouds.draw(
    types.SimpleNamespace(layout=t.FakeLayout(log)), types.SimpleNamespace(world=world, scene=scene)
)
props = [name for kind, name in log if kind == "prop"]
check("coverage_measure" in props, str(log))
check(props.index("coverage_measure") == props.index("coverage") + 1, f"beside coverage: {props}")

# A new cloud type loads its preset and keeps the measure the user chose.
layer.coverage_measure = "area"
layer.cloud_type = "altocumulus"
check(layer.coverage_measure == "area", "the type's preset keeps the measure")

# The frame's scene JSON carries it through the core, and the layer built from it is
# calibrated to that measure (altocumulus at 0.5: the two differ by about 0.2).
shares = {}
for measure in ("area", "dome"):
    layer.coverage_measure = measure
    layer.coverage = 0.5
    text = aerial_scene.scene_json(scene, native)
    d = json.loads(text)["clouds"]["layers"][0]
    check(d["coverage_measure"] == measure, f"scene JSON {d}")
    built = native.CloudLayer(
        cloud_type=d["cloud_type"], coverage=d["coverage"], coverage_measure=d["coverage_measure"]
    )
    check(built.coverage_measure == measure, built.coverage_measure)
    shares[measure] = (built.covered_fraction(), built.dome_fraction())
    print(
        f"coverage_measure {measure}: area share {shares[measure][0]:.3f}, dome share {shares[measure][1]:.3f}"
    )
check(abs(shares["area"][0] - 0.5) < 0.02, f"area: the area share is the setting {shares}")
check(abs(shares["dome"][1] - 0.5) < 0.02, f"dome: the dome share is the setting {shares}")
check(shares["dome"][0] < shares["area"][0] - 0.1, f"the dome layer covers less area {shares}")
check(cloud_scene.clouds_section(scene)["layers"][0]["coverage_measure"] == "dome", "section")
t.done("test_cloud_coverage_measure")
