# SPDX-License-Identifier: Apache-2.0
"""The world's sun disc, drawn by shader nodes from the view direction: a 1000 mm lens aimed
at the sun, with the world image at 256 x 128 (one texel is 3 times the disc's diameter),
renders (Cycles, 160 x 160, 16 samples) a round disc of the sun's angular size,
limb-darkened by the core's law, whose integrated energy is the direct irradiance
`welkin.sun` gives the lamp; and EEVEE renders the disc too, of the same size (its energy
checked where EEVEE's buffers hold it: 3.x; EEVEE Next clips at the half-float 65504). No
disc image in the file (an older file's is dropped). In an `-a` render of an animated sun,
each frame's disc is where that frame's lamp points. In EEVEE the disc lights nothing (a
grey plane renders the same with it shown or hidden; without its Is Camera Ray gate it would
light the plane).

Measured on the Cycles render, with the pixel solid angle of a perspective camera
(dOmega = p^2 f / (f^2 + x^2 + y^2)^(3/2), p the pixel pitch on the sensor):
  - energy: sum of (L - sky) dOmega over the pixels within 1.5 disc radii, per channel,
    against direct_irradiance_rgb: within 1 % (the pixel filter moves light between pixels
    but keeps its sum; Monte-Carlo noise of 16 samples over ~900 pixels is far smaller);
  - size: the disc's solid angle, each pixel counted by its coverage (its radiance over the
    profile's radiance at its angle, at most 1), against 2 pi (1 - cos alpha): within 3 %
    (the image of the disc is 33 pixels across); its centroid within 0.05 alpha of the sun's
    direction; round: the second moments along the image's two axes within 3 %;
  - limb darkening: the mean radiance within 0.3 alpha over the mean at 0.8-0.9 alpha,
    against the same ratio of the profile averaged over the same pixels: within 3 %.
"""

import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender import compat  # noqa: E402

ELEVATION, AZIMUTH = 30.0, 60.0
N = 160  # pixels across
LENS_MM, SENSOR_MM = 1000.0, 36.0
scene, sun = T.new_scene(ELEVATION, AZIMUTH, resolution="256")
T.panoramic_camera(scene, N, N, samples=16)  # the render settings; the camera follows
cam = scene.camera
cam.data.type = "PERSP"
cam.data.lens = LENS_MM
cam.data.sensor_width = SENSOR_MM
cam.data.sensor_fit = "HORIZONTAL"
cam.data.clip_end = 1e6
s = np.array(T.sun_direction(ELEVATION, AZIMUTH))
cam.rotation_mode = "QUATERNION"
cam.rotation_quaternion = Vector((0.0, 0.0, -1.0)).rotation_difference(Vector(s))
scene.cycles.filter_width = 1.5  # a normal pixel filter: it keeps the energy's sum
bpy.context.view_layer.update()
bpy.ops.welkin.update_sky()
settings = scene.world.welkin

# A file saved by a version that drew the disc from an image: its image and node go.
old_image = bpy.data.images.new("Welkin Sun Disc", 8, 4, float_buffer=True)
old_image["welkin_role"] = "disc"
settings.disc_image = old_image
old_node = scene.world.node_tree.nodes.new("ShaderNodeTexEnvironment")
old_node["welkin_role"] = "disc_texture"
old_node.image = old_image
settings.last_key = ""
bpy.ops.welkin.update_sky()
T.check(
    settings.disc_image is None and not any(i.get("welkin_role") == "disc" for i in bpy.data.images),
    "a sun-disc image is still in the file",
)
T.check(
    not any(
        n.bl_idname == "ShaderNodeTexEnvironment" and n.get("welkin_role") != "sky_texture"
        for n in scene.world.node_tree.nodes
    ),
    "a second environment texture",
)

atm = welkin.Atmosphere.preset(welkin.Atmosphere.preset_names()[0])  # the add-on's default
core = welkin.sun(atm, 0.0, s)
E = np.asarray(core.direct_irradiance_rgb)
alpha = float(atm.sun_angular_radius_rad)
# The core's disc: L_j(mu) = centre_radiance_rgb[j] sum_k b[j, k] mu^k.
core_coefficients = (np.asarray(core.limb_coefficients_rgb) * np.asarray(core.centre_radiance_rgb)[:, None]).T

# Every pixel's direction and solid angle (top row first, as the EXR is read).
R = np.array(cam.matrix_world.to_3x3())
pitch = SENSOR_MM / N
jj, ii = np.mgrid[0:N, 0:N]
x = (ii + 0.5 - N / 2) * pitch
y = (N / 2 - jj - 0.5) * pitch
d = np.stack([x, y, np.full_like(x, -LENS_MM)], axis=-1) @ R.T
d /= np.linalg.norm(d, axis=-1, keepdims=True)
omega = pitch**2 * LENS_MM / (LENS_MM**2 + x**2 + y**2) ** 1.5
rho = np.arcsin(np.clip(np.linalg.norm(np.cross(d, s), axis=-1), 0.0, 1.0))


def profile(rho_rad):
    """The core's disc radiance (..., 3) at angle rho from its centre."""
    t = np.minimum(np.sin(rho_rad) / math.sin(alpha), 1.0)
    mu = np.sqrt(1.0 - t * t)
    return np.moveaxis(np.polynomial.polynomial.polyval(mu, core_coefficients), 0, -1)


def measure(img, name):
    disc_zone = rho < 1.5 * alpha
    sky = np.median(img[(rho > 2.0 * alpha)], axis=0)
    light = img - sky
    energy = (light[disc_zone] * omega[disc_zone, None]).sum(axis=0)
    return energy, light, disc_zone, sky


path = T.TMP / "disc_cycles.exr"
T.render_still(scene, path)
img = T.read_rgb_exr(welkin, path)
T.check(np.isfinite(img).all(), "Cycles: non-finite pixels")
energy, light, zone, sky = measure(img, "Cycles")
err = energy / E - 1.0
print(
    f"Cycles: disc energy {energy} W m^-2, welkin.sun direct irradiance {E}, "
    f"error {np.round(100 * err, 3)} %  (sky beside the disc {sky})"
)
T.check(np.all(np.abs(err) < 0.01), f"disc energy off by {err}")

g = light[..., 1]
ref = profile(np.minimum(rho, alpha))[..., 1]
coverage = np.clip(g / ref, 0.0, 1.0) * zone
area = float((coverage * omega).sum())
area_ref = 2.0 * math.pi * (1.0 - math.cos(alpha))
print(f"Cycles: disc solid angle {area:.4e} sr, the sun's {area_ref:.4e} sr, ratio {area / area_ref:.4f}")
T.check(abs(area / area_ref - 1.0) < 0.03, f"disc solid angle ratio {area / area_ref:.4f}")
w = g * zone * omega
centroid = (d * w[..., None]).sum(axis=(0, 1)) / w.sum()
off = math.acos(min(1.0, float(np.dot(centroid / np.linalg.norm(centroid), s))))
mx = (w * x**2).sum() / w.sum() - ((w * x).sum() / w.sum()) ** 2
my = (w * y**2).sum() / w.sum() - ((w * y).sum() / w.sum()) ** 2
print(f"Cycles: centroid {off / alpha:.4f} alpha from the sun; second moments x/y {mx / my:.4f}")
T.check(off < 0.05 * alpha, f"disc centre {off / alpha:.3f} alpha off the sun's direction")
T.check(abs(mx / my - 1.0) < 0.03, f"disc not round: second moments x/y {mx / my:.4f}")

centre, ring = rho < 0.3 * alpha, (rho > 0.8 * alpha) & (rho < 0.9 * alpha)
measured = light[centre].mean(axis=0) / light[ring].mean(axis=0)
expected = profile(rho[centre]).mean(axis=0) / profile(rho[ring]).mean(axis=0)
print(f"Cycles: limb darkening centre / 0.8-0.9 alpha: rendered {measured}, model {expected}")
T.check(
    np.all(np.abs(measured / expected - 1.0) < 0.03) and np.all(expected > 1.2),
    f"limb darkening {measured} against the model's {expected}",
)

# EEVEE: the same view shows the disc (a world shader evaluated per pixel).
scene.render.engine = compat.eevee_engine_id()
if hasattr(scene.eevee, "taa_render_samples"):
    scene.eevee.taa_render_samples = 16
path = T.TMP / "disc_eevee.exr"
T.render_still(scene, path)
img = T.read_rgb_exr(welkin, path)
energy_e, light_e, _zone, sky_e = measure(img, "EEVEE")
T.check(np.isfinite(img).all(), "EEVEE: non-finite pixels")
# EEVEE Next (4.2+) renders into half floats: the disc's radiance (~1e7 W m^-2 sr^-1 at
# exposure 1) is clipped at 65504 there, so its shape is measured with that ceiling and its
# energy only where it is not clipped (EEVEE of 3.x). 4.2-5.2 clip each channel there;
# 5.3 scales the colour as a whole (its hue kept), so that only the brightest channel
# reaches 65504: the shape is measured on the channel that reaches the ceiling.
HALF_MAX = 65504.0
c = int(np.argmax(img.reshape(-1, 3).max(axis=0)))
clipped = abs(float(img[..., c].max()) / HALF_MAX - 1.0) < 0.01
ref_c = profile(np.minimum(rho, alpha))[..., c]
ceiling = np.minimum(ref_c, 0.99 * HALF_MAX) if clipped else ref_c
area_e = float((np.clip(light_e[..., c] / ceiling, 0.0, 1.0) * zone * omega).sum())
err_e = energy_e / E - 1.0
print(
    f"EEVEE ({scene.render.engine}): disc solid angle ratio {area_e / area_ref:.4f}, "
    f"energy {energy_e} W m^-2 ({'clipped at 65504' if clipped else 'error'} "
    f"{np.round(100 * err_e, 3)} %)"
)
T.check(abs(area_e / area_ref - 1.0) < 0.05, f"EEVEE: disc solid angle ratio {area_e / area_ref}")
T.check(clipped or np.all(np.abs(err_e) < 0.01), f"EEVEE: disc energy off by {err_e}")

# The disc lights nothing in EEVEE (the lamp does; EEVEE Next would otherwise fold a bright
# world texel into a sun light, World.sun_threshold): a grey plane seen from above, the lamp
# off, renders the same with the disc shown and hidden; the same disc with its Is Camera
# Ray gate removed lights it (the control that the check can fail).
settings.sync_lamp = False
sun.data.energy = 0.0
bpy.ops.mesh.primitive_plane_add(size=50.0, location=(0.0, 0.0, -1.0))
cam.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)  # looking down
cam.data.lens = 50.0


def plane_radiance(show, gated=True):
    settings.show_sun_disc = show
    bpy.ops.welkin.update_sky()
    if not gated:
        tree = scene.world.node_tree
        bg = next(n for n in tree.nodes if n.get("welkin_role") == "disc_background")
        for link in list(bg.inputs["Strength"].links):
            tree.links.remove(link)
        bg.inputs["Strength"].default_value = 1.0
    path = T.TMP / f"plane_{show}_{gated}.exr"
    T.render_still(scene, path)
    return float(T.read_rgb_exr(welkin, path)[..., 1].mean())


# The control needs a disc that lights the plane measurably in EEVEE's world lighting: the
# clearest air's (with the default clear_day haze the un-gated disc's share is within the
# bpy builds' EEVEE noise).
default_preset, settings.preset = settings.preset, "bruneton2017"
shown, hidden, ungated = plane_radiance(True), plane_radiance(False), plane_radiance(True, False)
print(f"EEVEE plane: disc shown {shown:.6g}, hidden {hidden:.6g}, un-gated {ungated:.6g}")
T.check(abs(shown - hidden) <= 1e-4 * hidden, f"the disc lights the plane: {shown} vs {hidden}")
T.check(ungated - hidden > 0.02 * hidden, f"the control failed: un-gated {ungated} vs {hidden}")
bpy.data.objects.remove(bpy.context.active_object)
settings.preset = default_preset
settings.show_sun_disc = True
settings.sync_lamp = True

# An animated sun in a separate `blender -b file.blend -a`: each frame's disc is where that
# frame's lamp points (the frame handler writes the disc's numbers into the nodes), within
# 0.1 alpha. A 200 mm lens (10 degrees) at 96 x 96 sees the sun at 30 and then 32 degrees.
scene.render.engine = "CYCLES"
cam.data.lens = 200.0
N = 96
scene.render.resolution_x = scene.render.resolution_y = N
scene.cycles.samples = 4
mid = np.array(T.sun_direction(31.0, AZIMUTH))
cam.rotation_quaternion = Vector((0.0, 0.0, -1.0)).rotation_difference(Vector(mid))
scene.frame_start, scene.frame_end = 1, 2
for f, e in ((1, 30.0), (2, 32.0)):
    T.aim_sun(sun, e, AZIMUTH)
    sun.keyframe_insert("rotation_quaternion", frame=f)
scene.frame_set(1)
bpy.ops.welkin.update_sky()
scene.render.filepath = str(T.TMP / "anim" / "f_####")
blend = T.TMP / "disc_animated.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
env["BLENDER_USER_SCRIPTS"] = str(T.scripts_dir())
env["BLENDER_USER_CONFIG"] = str(T.TMP / "config")
run = subprocess.run(
    [*T.blender_command(), "-b", "--factory-startup", str(blend), "--addons", "welkin", "-a"],
    env=env,
    capture_output=True,
    text=True,
    timeout=300,
)
T.check(
    run.returncode == 0 and "Traceback" not in run.stdout + run.stderr,
    f"-a render failed:\n{(run.stdout + run.stderr)[-3000:]}",
)
R = np.array(cam.matrix_world.to_3x3())
pitch = SENSOR_MM / N
jj, ii = np.mgrid[0:N, 0:N]
d = np.stack([(ii + 0.5 - N / 2) * pitch, (N / 2 - jj - 0.5) * pitch, np.full((N, N), -200.0)], axis=-1) @ R.T
d /= np.linalg.norm(d, axis=-1, keepdims=True)
for f, e in ((1, 30.0), (2, 32.0)):
    img = T.read_rgb_exr(welkin, T.TMP / "anim" / f"f_{f:04d}.exr")[..., 1]
    w = np.clip(img - np.median(img), 0.0, None)
    w = w * (w > 0.01 * w.max())
    c = (d * w[..., None]).sum(axis=(0, 1))
    want = np.array(T.sun_direction(e, AZIMUTH))
    off = math.acos(min(1.0, float(np.dot(c / np.linalg.norm(c), want))))
    print(f"-a frame {f}: disc centroid {off / alpha:.3f} alpha from that frame's sun ({e} deg)")
    T.check(off < 0.1 * alpha, f"frame {f}: the disc is {off / alpha:.2f} alpha off its sun")
T.done("test_addon_sun_disc")
