# SPDX-License-Identifier: Apache-2.0
"""The render engine "WELKIN" renders headless (`blender -b scene.blend -E WELKIN -f 1`)
the same plate as the CLI (`welkin plate --scene`), with its passes; a panoramic camera
renders the exported HDRI; without the add-on Blender silently falls back and the test
tells (the output lacks Welkin's passes); the passes reach Blender by a buffer copy in every
version (render_engine._set_rect), not by assignment.

Tolerances: Combined against the CLI's plate from the same scene JSON, 1 % per pixel
(relative to max(value, 1e-3 x the image mean)); both are the same core call, so any
difference is the add-on's (rows flipped, passes mixed up, a camera or unit written
wrong). Panorama against the HDRI (bpy.ops.welkin.export_hdri, same width): sky pixels
more than 2 degrees from the sun within 1 % (the same sky method on the same pixel-centre
directions); the disc and the ground are printed, not asserted: the HDRI splats the disc
per equirect pixel and gives ground pixels the sky method's path radiance, the plate
point-samples the disc and shows the ground through the froxel aerial perspective.
"""

import math
import os
import pathlib
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402

addon, native = t.install_addon()
from welkin import plate  # noqa: E402
from welkin.blender import compat  # noqa: E402
from welkin.blender.engine import render_engine  # noqa: E402

check = t.check
CLI = t.ROOT / "build" / "welkin"
PASSES = ("Combined",) + plate.PASS_NAMES


def read_layers(path):
    """{pass name: (H, W, C) array} of a Blender multilayer EXR (layer "ViewLayer")."""
    pixels, names = native.read_exr(str(path))
    out = {}
    for name in PASSES + ("Depth",):
        chans = [c for c in ("R", "G", "B", "A", "Z", "V") if f"ViewLayer.{name}.{c}" in names]
        if chans:
            out[name] = np.stack([pixels[..., names.index(f"ViewLayer.{name}.{c}")] for c in chans], axis=-1)
    return out, names


def is_welkin_render(names):
    """A Welkin frame has Welkin's passes; Blender's fallback engine has not."""
    return all(any(n.startswith(f"ViewLayer.{p}.") for n in names) for p in plate.PASS_NAMES)


def render_headless(blend, out_stem, *, addon_enabled=True, engine_flag=True, expect_rc=0):
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(t.scripts_dir()))
    env.pop("PYTHONPATH", None)
    cmd = [*t.blender_command(), "-b", str(blend)]
    if addon_enabled:
        cmd += ["--addons", "welkin"]
    if engine_flag:
        cmd += ["-E", "WELKIN"]
    cmd += ["-o", str(out_stem) + "_####", "-F", "OPEN_EXR_MULTILAYER", "-f", "1"]
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    print(run.stdout[-1500:], run.stderr[-1500:])
    if expect_rc is not None:
        check(run.returncode == expect_rc, f"blender exited {run.returncode}")
    return pathlib.Path(str(out_stem) + "_0001.exr"), run


def cli_plate(scene_json_text, path):
    scene_path = path.with_suffix(".json")
    scene_path.write_text(scene_json_text)
    subprocess.run([str(CLI), "plate", "--scene", str(scene_path), "-o", str(path)], check=True)
    pixels, names = native.read_exr(str(path))
    return {
        "Combined": np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1),
        "Welkin.Sky": np.stack([pixels[..., names.index(f"Welkin.Sky.{c}")] for c in "RGB"], -1),
    }


def relative_error(a, b):
    floor = 1e-3 * float(np.mean(np.abs(b)))
    return np.abs(a - b) / np.maximum(np.abs(b), floor)


def setup(scene):
    scene.render.engine = "WELKIN"
    scene.render.resolution_x, scene.render.resolution_y = 96, 64
    scene.render.resolution_percentage = 100
    settings = scene.render.image_settings
    compat.set_file_format(settings, "OPEN_EXR_MULTILAYER")
    settings.color_depth = "32"
    scene.world.welkin.method = "lut"


def scene_json(scene):
    return render_engine.scene_description_json(scene, bpy.context.evaluated_depsgraph_get(), native)


# A perspective camera 50 m up looking along +X, 2 degrees down: ground and sky, with the
# sun's disc in view.
scene, sun = t.new_scene(sun_elevation_deg=6.0, sun_azimuth_deg=5.0, camera_z=50.0)
setup(scene)
cam = scene.camera
cam.rotation_mode = "XYZ"
cam.rotation_euler = (math.radians(88.0), 0.0, math.radians(-90.0))
bpy.context.view_layer.update()
blend = t.TMP / "engine_persp.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
exr, _run = render_headless(blend, t.TMP / "persp")
layers, names = read_layers(exr)
check(is_welkin_render(names), f"not a Welkin render; channels: {names}")
for name in PASSES:
    check(name in layers, f"pass {name} missing; channels: {names}")
    check(
        np.all(np.isfinite(layers[name][..., :3])) or name == "Welkin.CloudDepth", f"pass {name} not finite"
    )
check(layers["Combined"].shape == (64, 96, 4), f"Combined shape {layers['Combined'].shape}")
ref = cli_plate(scene_json(scene), t.TMP / "persp_cli.exr")
err = relative_error(layers["Combined"][..., :3], ref["Combined"])
print(f"perspective: Combined vs CLI plate, max relative error {err.max():.3g}")
check(err.max() < 0.01, f"Combined differs from the CLI's plate by {err.max():.3g}")
sky_rows = np.isinf(native.camera_plate(scene_json(scene))["depth"]).mean()
check(0.1 < sky_rows < 0.9, f"the view should hold sky and ground, sky fraction {sky_rows}")
T = layers["Welkin.AerialTransmittance"]
check(np.all((T >= 0) & (T <= 1)), "transmittance outside [0, 1]")
# Combined = Sky + Inscatter + T x G: on sky pixels Sky alone (T = 1, no inscatter); on the
# ground, the lit ground G (albedo / pi x irradiance, camera_plate.hpp) seen through the air.
depth = layers["Depth"][..., 0] if "Depth" in layers else None
rest = layers["Combined"][..., :3] - layers["Welkin.Sky"][..., :3] - layers["Welkin.AerialInscatter"]
ground_px = np.isfinite(depth) & (depth < 1e9) if depth is not None else (T[..., 0] < 1.0)
check(
    np.allclose(rest[~ground_px], 0.0, atol=1e-6 * float(np.abs(layers["Combined"]).max())),
    "Combined != Sky + AerialInscatter on sky pixels",
)
check(
    float((rest[ground_px] / np.maximum(T[ground_px], 1e-12)).min()) > 0.0,
    "the ground below the horizon is not lit (Combined - Sky - Inscatter <= 0)",
)
peak = float(layers["Welkin.Sky"][..., 1].max())
check(peak > 100 * float(np.median(layers["Welkin.Sky"][..., 1])), "no sun disc in view")

# Without the add-on, a .blend saved with Welkin as its engine renders with Blender's
# fallback engine and exits 0 (Blender 3.4 prints only "Engine 'WELKIN' not available"):
# the output lacks Welkin's passes, which is how a farm script must tell.
exr_off, run_off = render_headless(
    blend, t.TMP / "fallback", addon_enabled=False, engine_flag=False, expect_rc=0
)
check(exr_off.exists(), "the fallback render wrote nothing")
_l, names_off = read_layers(exr_off)
check(not is_welkin_render(names_off), f"fallback render has Welkin's passes? {names_off}")
print(f"fallback without the add-on: exit 0, channels {names_off}: detected (no Welkin passes)")
# With `-E WELKIN` and no add-on, Blender 3.4 refuses ("engine not found") and renders
# nothing.
exr_off2, run_off2 = render_headless(blend, t.TMP / "fallback_e", addon_enabled=False, expect_rc=None)
check(
    not (exr_off2.exists() and is_welkin_render(read_layers(exr_off2)[1])),
    "-E WELKIN without the add-on wrote a Welkin frame?",
)
print(f"-E WELKIN without the add-on: exit {run_off2.returncode}, frame written: {exr_off2.exists()}")

# Orthographic, in this Blender: the same plate as the CLI.
cam.data.type = "ORTHO"
cam.data.ortho_scale = 40.0
bpy.context.view_layer.update()
scene.render.filepath = str(t.TMP / "ortho.exr")
bpy.ops.render.render(write_still=True)
layers_o, names_o = read_layers(t.TMP / "ortho.exr")
check(is_welkin_render(names_o), f"ortho: not a Welkin render: {names_o}")
ref_o = cli_plate(scene_json(scene), t.TMP / "ortho_cli.exr")
err_o = relative_error(layers_o["Combined"][..., :3], ref_o["Combined"])
print(f"orthographic: Combined vs CLI plate, max relative error {err_o.max():.3g}")
check(err_o.max() < 0.01, f"ortho Combined differs from the CLI's plate by {err_o.max():.3g}")

# Panorama at the origin's vertical, 2 m up: the exported HDRI.
t.panoramic_camera(scene, 128, 64)
cam.location = (0.0, 0.0, 2.0)
setup(scene)
scene.render.resolution_x, scene.render.resolution_y = 128, 64
bpy.context.view_layer.update()
blend_p = t.TMP / "engine_pano.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend_p))
exr_p, _ = render_headless(blend_p, t.TMP / "pano")
pano, names_p = read_layers(exr_p)
check(is_welkin_render(names_p), "pano: not a Welkin render")
hdri_path = t.TMP / "hdri.exr"
bpy.ops.welkin.export_hdri(filepath=str(hdri_path), width=128)
hdri = t.read_rgb_exr(native, hdri_path)
j, i = np.mgrid[0:64, 0:128]
lon = math.pi - 2 * math.pi * (i + 0.5) / 128
lat = math.pi / 2 - math.pi * (j + 0.5) / 64
dirs = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], -1)
s = np.array(t.sun_direction(6.0, 5.0))
away = np.degrees(np.arccos(np.clip(dirs @ s, -1, 1))) > 2.0
sky = np.isinf(native.camera_plate(scene_json(scene))["depth"])
err_p = relative_error(pano["Combined"][..., :3], hdri)
print(
    f"panorama vs HDRI: sky pixels away from the sun max relative error "
    f"{err_p[sky & away].max():.3g}; ground pixels median {np.median(err_p[~sky]):.3g} "
    f"max {err_p[~sky].max():.3g}"
)
check(err_p[sky & away].max() < 0.01, f"panorama differs from the HDRI by {err_p[sky & away].max():.3g}")
omega = (2 * math.pi / 128) * (math.pi / 64) * np.cos(lat)
disc = ~away & sky
e_pano = float((pano["Welkin.Sky"][..., 1] * omega)[disc].sum())
e_hdri = float((hdri[..., 1] * omega)[disc].sum())
print(f"sun region energy (G, within 2 deg): plate {e_pano:.4g}, HDRI {e_hdri:.4g}")


# How the engine hands its passes to Blender (render_engine._set_rect): by foreach_set, the
# buffer's copy, in the shape this Blender takes, never by assignment, which converts every
# value (a 1920 x 1080 frame took 17 s more so in Blender 5.3). A probe engine writes a band
# of 1920 x 64 of known values into its Combined pass; they must read back exactly.
class _RectProbe(bpy.types.RenderEngine):
    bl_idname = "WELKIN_TEST_RECT_PROBE"
    bl_label = "Welkin rect probe"
    written = None

    def render(self, depsgraph):
        w, h = depsgraph.scene.render.resolution_x, depsgraph.scene.render.resolution_y
        band = self.begin_result(0, 0, w, h)
        rect = (np.arange(w * h * 4).reshape(-1, 4) / (w * h)).astype(np.float32)
        p = band.layers[0].passes["Combined"]
        way = render_engine._set_rect(p, rect)
        back = np.empty(w * h * 4, np.float32)
        try:
            p.rect.foreach_get(back)
        except TypeError:  # Blender 3.4: the (n, 4) shape
            back = back.reshape(-1, 4)
            p.rect.foreach_get(back)
        type(self).written = (way, bool(np.array_equal(back.reshape(-1, 4), rect)))
        self.end_result(band)


bpy.utils.register_class(_RectProbe)
probe_scene = bpy.data.scenes.new("rect probe")
probe_scene.camera = bpy.data.objects.new("rect probe camera", bpy.data.cameras.new("rect probe camera"))
probe_scene.collection.objects.link(probe_scene.camera)
probe_scene.render.engine = _RectProbe.bl_idname
probe_scene.render.resolution_x, probe_scene.render.resolution_y = 1920, 64
probe_scene.render.resolution_percentage = 100
bpy.ops.render.render(scene=probe_scene.name)
print(f"passes handed over: {_RectProbe.written}")
check(_RectProbe.written is not None, "the probe engine did not run")
check(_RectProbe.written[0] != "assigned", f"passes handed over by assignment ({bpy.app.version_string})")
check(_RectProbe.written[1], "the pass reads back other values than were written")
bpy.utils.unregister_class(_RectProbe)
t.done("test_engine_render")
