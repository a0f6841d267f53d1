# SPDX-License-Identifier: Apache-2.0
"""A VDB cumulus under the add-on's own world and synced sun lamp: Cycles against the WELKIN
engine's cloud pass, and the pieces between them, in one Blender process.

    PYTHONPATH=build blender -b --factory-startup --python-use-system-env \
        --python bench/clouds/cycles_addon_lighting.py -- [--size 96 64] [--samples 128] \
        [--bounces 48] [--paths 256] [--sigma 0.0148] [--csv FILE]

The scene: the cumulus of bench/cycles_volume.py scaled 2.7 x (about 1.2 x 0.9 km), its
centre 5 km up and 6 km away along +X; the camera on the ground (1.5 m) looking at it; the
sun 30 degrees up, 60 degrees to the left of the view (front-left); the add-on's sky
(Update Sky: the world texture and the synced lamp's strength, colour and angle). Cycles
renders the volume (Welkin's phase 0.8 HG(0.8) + 0.2 HG(-0.3), albedo 1) with
film_transparent, so its RGB is the cloud's premultiplied radiance, no world behind; the
engine's pass Welkin.Clouds is the same quantity (welkin.cloud_passes on the engine's own
scene description).

Rows (luminance ratios over the cloud's pixels, Cycles' alpha > 0.05; "sunlit" is the half
of the cloud's pixels towards the sun's direction on the image, "shadow" the other half,
"base" the bottom fifth of the cloud's rows):

* engine / Cycles: the issue's comparison (the air between the camera and the cloud
  included in the engine's pass, as the engine renders it);
* engine without the air / Cycles: the same pass with every cloud at "sky depth"
  (aerial.sky_depth_m = 1 m), so no air is applied in front of it;
* fast / reference: welkin.cloud_radiance's march against its path tracer under the same
  atmosphere light (green channel, 560 nm), no air in either.
"""

import argparse
import atexit
import json
import math
import os
import pathlib
import shutil
import sys
import tempfile

import bpy
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import addon_testing as T  # noqa: E402

# Blender's command line passes the script's arguments after "--"; tests/blender/bpy_blender.py
# (PyPI's bpy) passes them alone.
argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
p = argparse.ArgumentParser()
p.add_argument("--size", type=int, nargs=2, default=(96, 64))
p.add_argument("--samples", type=int, default=128)
p.add_argument("--bounces", type=int, default=48)
p.add_argument("--paths", type=int, default=256, help="reference paths per pixel (0: skip)")
p.add_argument("--scale", type=float, default=2.7)
p.add_argument("--sigma", type=float, default=0.04 / 2.7, help="sigma_t at the densest voxel, m^-1")
p.add_argument("--lobes", default="welkin", choices=("welkin", "one"))
p.add_argument("--lamp", default="ground", choices=("ground", "cloud"),
               help="the lamp as the add-on syncs it (the sun at the ground) or the sun at the cloud's altitude")
p.add_argument("--csv", default="")
args = p.parse_args(argv)

addon, native = T.install_addon()
import cycles_volume as cv  # noqa: E402
from welkin.blender.engine import render_engine  # noqa: E402
from welkin.blender.sky import scene_sun  # noqa: E402

W, H = args.size
LOBES = ((0.8, 0.8), (-0.3, 0.2)) if args.lobes == "welkin" else ((cv.G, 1.0),)
CLOUD_AT = (6000.0, 0.0, 5000.0)

tmp = tempfile.mkdtemp(prefix="welkin_cycles_addon_lighting_")
atexit.register(shutil.rmtree, tmp, ignore_errors=True)
vdb = os.path.join(tmp, "cumulus.vdb")
cv.write_cumulus(vdb, voxel_m=6.0 * args.scale, radius_m=220.0 * args.scale)

scene, sun = T.new_scene(sun_elevation_deg=30.0, sun_azimuth_deg=60.0, resolution="512", camera_z=1.5)
world = scene.world
world.welkin.method = "lut"
vol = bpy.data.volumes.new("Cloud")
vol.filepath = vdb
vol.render.precision = "FULL"
vol.render.clipping = 0.0
vol.render.space = "OBJECT"
vol.render.step_size = 0.0
ob = bpy.data.objects.new("Cloud", vol)
ob.location = CLOUD_AT
scene.collection.objects.link(ob)
vol.materials.append(cv._cloud_material(args.sigma / 1.0, LOBES))
ob.welkin_cloud.enabled = True
ob.welkin_cloud.density_scale = args.sigma
cam = scene.camera
cam.data.lens = 150.0
cam.data.clip_start, cam.data.clip_end = 0.1, 1e6
cv.look_at(cam, CLOUD_AT)
bpy.context.view_layer.update()
bpy.ops.welkin.update_sky()
if args.lamp == "cloud":
    import welkin as _w
    from welkin import sky_request as _sr

    _req, _l, _ = scene_sun.request_for(scene, world.welkin, None)
    _atm = _sr.build_atmosphere(_req, native)
    e_ground = np.array(_w.sun(_atm, _req.altitude_m, tuple(_req.sun_direction)).direct_irradiance_rgb)
    e_cloud = np.array(_w.sun(_atm, CLOUD_AT[2], tuple(_req.sun_direction)).direct_irradiance_rgb)
    print("sun RGB irradiance at the ground", e_ground, "at the cloud", e_cloud)
    world.welkin.sync_lamp = False  # else the render's handler writes the ground's values back
    sun.data.energy = float(e_cloud.max())
    sun.data.color = tuple(float(v) for v in e_cloud / e_cloud.max())
print("lamp:", sun.data.energy, tuple(sun.data.color), math.degrees(sun.data.angle), world.welkin.status)

r = scene.render
r.engine = "CYCLES"
r.resolution_x, r.resolution_y, r.resolution_percentage = W, H, 100
r.film_transparent = True
r.filter_size = 0.01
r.image_settings.file_format = "OPEN_EXR"
r.image_settings.color_mode = "RGBA"
r.image_settings.color_depth = "32"
scene.view_settings.view_transform = "Standard"
c = scene.cycles
c.device = "CPU"
c.samples = args.samples
c.use_adaptive_sampling = False
c.use_denoising = False
c.max_bounces = c.volume_bounces = c.transparent_max_bounces = args.bounces
c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 0
c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
c.light_sampling_threshold = 0.0
c.volume_max_steps = 4096
c.pixel_filter_type = "BOX"
c.filter_width = 0.01
cyc = cv.render(scene, os.path.join(tmp, "cycles.exr"))

depsgraph = bpy.context.evaluated_depsgraph_get()
text = render_engine.scene_description_json(scene, depsgraph, native)
desc = json.loads(text)
if args.lobes == "one":
    desc["clouds"]["scattering"] = {"albedo": 1.0, "g_forward": cv.G, "g_back": 0.0, "w_forward": 1.0}
    text = json.dumps(desc)
PHASE = dict(g_forward=cv.G, w_forward=1.0) if args.lobes == "one" else {}
print("clouds:", json.dumps(desc.get("clouds", {}).get("volumes", []))[:400])
passes = native.cloud_passes(native.SceneDescription.from_json_string(text))
eng = passes["Welkin.Clouds"]
print("keys:", list(desc))
desc.setdefault("aerial", {})["sky_depth_m"] = 1.0
passes = native.cloud_passes(native.SceneDescription.from_json_string(json.dumps(desc)))
eng_noair = passes["Welkin.Clouds"]

Y = np.array([0.2126, 0.7152, 0.0722])


def lum(x):
    return x[..., :3] @ Y


alpha = cyc[..., 3]
mask = alpha > 0.05
rows = np.nonzero(mask.any(axis=1))[0]
# The sun's direction on the image: project the sun direction onto the camera's right/up.
m = np.array(cam.matrix_world.to_3x3())
right, up = m[:, 0], m[:, 1]
s = np.array(T.sun_direction(30.0, 60.0))
sx, sy = float(s @ right), float(s @ up)
yy, xx = np.mgrid[0:H, 0:W].astype(float)
cxm, cym = xx[mask].mean(), yy[mask].mean()
toward = (xx - cxm) * sx - (yy - cym) * sy  # image rows grow downwards
sunlit = mask & (toward > np.median(toward[mask]))
shadow = mask & ~sunlit & mask
base = mask & (yy >= rows.min() + 0.8 * (rows.max() - rows.min() + 1))
regions = {"all": mask, "sunlit": sunlit, "shadow": shadow, "base": base}

out = []


def compare(name, x, ref):
    a, b = lum(x), lum(ref)
    line = [name]
    for k, reg in regions.items():
        line.append((k, float(a[reg].sum() / b[reg].sum())))
    q = a[mask] / np.maximum(b[mask], 1e-12)
    line += [("p10", float(np.percentile(q, 10))), ("p50", float(np.median(q))), ("p90", float(np.percentile(q, 90)))]
    print(name + ": " + ", ".join(f"{k} {v:.3f}" for k, v in line[1:]), flush=True)
    out.append(line)


print(f"cloud pixels {mask.sum()}, sun on the image ({sx:+.2f}, {sy:+.2f})")
compare("engine/cycles", eng, cyc)
compare("engine_noair/cycles", eng_noair, cyc)
compare("engine/engine_noair", eng, eng_noair)

if args.paths:
    import welkin

    request, _lamp, _w = scene_sun.request_for(scene, world.welkin, None)
    from welkin import sky_request

    atm = sky_request.build_atmosphere(request, native)
    origin, dirs = cv.camera_rays(scene)
    mw = np.array(ob.matrix_world)
    clouds = welkin.VdbClouds(vdb, density_scale=args.sigma, matrix_world=mw, placement=desc["clouds"]["volumes"][0].get("placement", "blender"))
    kw = dict(origin=(0.0, 0.0, 0.0))
    alt = request.altitude_m
    sd = tuple(request.sun_direction)
    o = np.array(origin)
    # cloud_radiance's origin is the observer's: move the cloud, not the camera.
    mw2 = mw.copy()
    mw2[:3, 3] -= o
    clouds = welkin.VdbClouds(vdb, density_scale=args.sigma, matrix_world=mw2, placement=desc["clouds"]["volumes"][0].get("placement", "blender"))
    Lf, Tf, _ = welkin.cloud_radiance(clouds, atm, alt, sd, dirs, method="fast", **kw, **PHASE)
    Lr, Tr, _ = welkin.cloud_radiance(clouds, atm, alt, sd, dirs, method="reference", paths=args.paths, seed=1, **kw, **PHASE)
    g = 1 if Lf.shape[1] > 1 else 0
    f = Lf[:, g].reshape(H, W)
    rr = Lr[:, g].reshape(H, W)
    for k, reg in regions.items():
        print(f"fast/reference {k}: {f[reg].sum() / rr[reg].sum():.3f}")
    q = f[mask] / np.maximum(rr[mask], 1e-12)
    print(f"fast/reference per pixel p10 {np.percentile(q, 10):.3f} p50 {np.median(q):.3f} p90 {np.percentile(q, 90):.3f}")
    print(f"alpha: cycles {alpha[mask].mean():.3f}, reference {(1 - Tr.reshape(H, W))[mask].mean():.3f}")
    # engine's march vs this march (same light?) on the green channel is not comparable in RGB;
    # the ratio of engine_noair to fast in luminance vs green shows the colour conversion only.
    np.savez(os.path.join(os.environ.get("WELKIN_DUMP", tmp), "dump.npz"), cyc=cyc, eng=eng, eng_noair=eng_noair, f=f, r=rr, mask=mask)
