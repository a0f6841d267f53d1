# SPDX-License-Identifier: Apache-2.0
"""A 1920 x 1080 plate with a VDB cloud: `welkin plate` against Cycles rendering the same
world and volume, one Blender process.

    PYTHONPATH=build blender -b --factory-startup --python-use-system-env \
        --python bench/cycles_plate_clouds.py -- [--samples 11] [--cli build/welkin] \
        [--csv bench/results/cycles_plate_clouds.csv]

Needs a `welkin plate` whose scene JSON takes "clouds" (the clouds-in-plate work, branch
cloudscene). The aerial demo's world, sun and camera (blend/make_aerial_demo.py, rendered
once small to get its scene JSON), the demo's meshes hidden, and the cumulus of
bench/cycles_volume.py scaled 3 x (about 1.4 km across, sigma_t up to 0.04/3 m^-1, so the
same optical depths) 2.5 km in front of the camera, its base ~400 m up. Cycles renders the
Welkin world texture, the sun lamp and the volume (one HG lobe g = 0.6, albedo 1, 1024
bounces) at --samples, by default 11: the sample count at which Cycles' median noise equals
the fast march's median error on this cumulus (bench/results/cycles_clouds.csv). The plate
lights the same cloud from the atmosphere (same phase): the same work for both, not the same
light, so only times are compared. Both whole calls (Cycles: sync, volume, render; the CLI:
process, LUTs, VDB, plate, EXR write), the same run.
"""

import argparse
import atexit
import json
import os
import runpy
import shutil
import subprocess
import sys
import tempfile
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
p = argparse.ArgumentParser()
p.add_argument("--samples", type=int, default=11)
p.add_argument("--width", type=int, default=1920)
p.add_argument("--cli", default=os.path.join(ROOT, "build", "welkin"))
p.add_argument("--csv", default=os.path.join(ROOT, "bench", "results", "cycles_plate_clouds.csv"))
args = p.parse_args(argv)
W, H = args.width, args.width * 9 // 16

out = tempfile.mkdtemp(prefix="welkin_cycles_plate_clouds_")
atexit.register(shutil.rmtree, out, ignore_errors=True)
sys.argv = [sys.argv[0], "--", "--out", out, "--size", "320", "--samples", "1"]
runpy.run_path(os.path.join(ROOT, "blend", "make_aerial_demo.py"), run_name="__main__")
import cycles_volume as cv  # noqa: E402
from welkin import native, scene_export  # noqa: E402  (the add-on's package)

welkin = native.module()
scene = bpy.context.scene
base = scene_export.file_base(bpy.path.abspath(scene.render.filepath))
with open(scene_export.frame_path(base, "scene", 1)) as f:
    desc = json.load(f)

vdb = os.path.join(out, "cumulus.vdb")
cv.write_cumulus(vdb)
SCALE, SIGMA = 3.0, 0.04 / 3.0
scene.welkin_aerial.enabled = False
for obj in scene.objects:
    if obj.type == "MESH":
        obj.hide_render = True
vol = bpy.data.volumes.new("Cloud")
vol.filepath = vdb
vol.render.precision = "FULL"
vol_obj = bpy.data.objects.new("Cloud", vol)
vol_obj.location = (2500.0, 0.0, 400.0 + 0.3 * 220.0 * SCALE)
vol_obj.scale = (SCALE, SCALE, SCALE)
scene.collection.objects.link(vol_obj)
vol.materials.append(cv._cloud_material(SIGMA, ((cv.G, 1.0),)))
bpy.context.view_layer.update()
r = scene.render
r.resolution_x, r.resolution_y, r.resolution_percentage = W, H, 100
c = scene.cycles
c.samples = args.samples
c.use_adaptive_sampling = False
c.max_bounces = c.volume_bounces = c.transparent_max_bounces = 1024
c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
c.volume_step_rate = 1.0

desc["resolution"] = {"x": W, "y": H, "percentage": 100}
desc["clouds"] = {
    "volumes": [
        {
            "name": "Cloud",
            "file": vdb,
            "grid": "density",
            "matrix_world": [list(row) for row in vol_obj.matrix_world],
            "density_scale": SIGMA,
        }
    ],
    "scattering": {"albedo": 1.0, "g_forward": cv.G, "w_forward": 1.0},
}
scene_json = os.path.join(out, "plate_clouds.json")
with open(scene_json, "w") as f:
    json.dump(desc, f, indent=1)

rows = []


def row(name, value, note=""):
    rows.append((name, value, note))
    print(f"cycles_plate_clouds: {name} = {value:.4g} {note}", flush=True)


plate = os.path.join(out, "plate.exr")
t = time.perf_counter()
run = subprocess.run(
    [args.cli, "plate", "--scene", scene_json, "-o", plate, "--overwrite"], capture_output=True, text=True
)
t_plate = time.perf_counter() - t
assert run.returncode == 0, run.stderr
px, names = welkin.read_exr(plate)
alpha = px[..., names.index("Welkin.Clouds.A")]
row("cloud_pixels_plate", float((alpha > 0.05).sum()), "px with cloud opacity > 0.05")
row("welkin_plate_s", t_plate, f"{W}x{H}, whole CLI call")

scene.render.filepath = os.path.join(out, "cycles.exr")
r.image_settings.file_format = "OPEN_EXR"
t = time.perf_counter()
bpy.ops.render.render(write_still=True)
t_cycles = time.perf_counter() - t
img, names = welkin.read_exr(os.path.join(out, "cycles.exr"))
row("cycles_s", t_cycles, f"{W}x{H}, {args.samples} spp, world + sun + volume")
row("cycles_over_plate", t_cycles / t_plate, "x")
row("load_average_1min", os.getloadavg()[0])
os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
with open(args.csv, "w") as f:
    f.write("name,value,note\n")
    for name, value, note in rows:
        f.write(f'{name},{value:.5g},"{note}"\n')
print(f"cycles_plate_clouds: wrote {args.csv}")
