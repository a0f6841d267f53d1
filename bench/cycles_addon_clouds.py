# SPDX-License-Identifier: Apache-2.0
"""A VDB cumulus under the add-on's own sky, rendered by Cycles and by Welkin for the same
pixels (used by bench/clouds/cycles_addon_lighting.py and
tests/blender/test_cycles_clouds_lighting.py; inside Blender, the add-on installed).

The scene: the cumulus of bench/cycles_volume.py written `scale` times larger (6 m voxels
become 6 x scale m: an unscaled object, since Blender 3.4's Cycles renders an object-scaled
volume thinner than sigma_t x the world path), its centre 5 km up and 6 km away along +X;
the camera on the ground looking at it; the sun lamp aimed, Update Sky run (the world
texture and the synced lamp). What each renderer gets:

* Cycles: the volume with Welkin's phase (`lobes`, albedo 1, sigma_t = density_scale x the
  grid's value per metre), film_transparent (RGB = the cloud's premultiplied radiance, no
  world behind), a 0.01 px Gaussian pixel filter, `bounces` volume bounces, no clamping or denoising;
  the world texture lights it, and the lamp. The add-on syncs the lamp to the sun at the
  camera's height; lamp="cloud" sets it to the sun's irradiance at the cloud's altitude
  (welkin.sun, the atmosphere's transmittance from there), the light Welkin gives the
  cloud, and turns Sync Lamp off so that the render's handler keeps it.
* The engine: welkin.cloud_passes on the render engine's own scene description
  (Welkin.Clouds, the same premultiplied radiance); with air=False every cloud is put at
  "sky depth" (aerial.sky_depth_m = 1 m), so the air between camera and cloud is left out,
  as Cycles has none.
* The reference: welkin.cloud_radiance(method="reference") for the camera's pixel rays under
  the atmosphere's light, converted to RGB as the engine converts the march.
"""

import contextlib
import json
import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cycles_volume as cv  # noqa: E402
from cloud_regions import image_regions  # noqa: E402

WELKIN_LOBES = ((0.8, 0.8), (-0.3, 0.2))  # Welkin's default CloudPhase: w HG(g), (g, w)
ONE_LOBE = ((cv.G, 1.0),)
CLOUD_AT = (6000.0, 0.0, 5000.0)
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec.709


def write_cloud(path, scale=2.7):
    cv.write_cumulus(path, voxel_m=6.0 * scale, radius_m=220.0 * scale)


def build(
    T,
    vdb,
    *,
    sigma,
    lobes,
    sun_elevation_deg,
    sun_azimuth_deg,
    camera,
    lens_mm,
    size,
    samples,
    bounces,
    seed=1,
    at=CLOUD_AT,
):
    """The scene (T: tests/blender/addon_testing.py, the caller's import), the volume object
    at `at` (its grid's own origin there), the camera aimed at it. Returns (scene, sun lamp,
    volume object)."""
    scene, sun = T.new_scene(
        sun_elevation_deg=sun_elevation_deg,
        sun_azimuth_deg=sun_azimuth_deg,
        resolution="512",
        camera_z=camera[2],
    )
    scene.world.welkin.method = "lut"
    vol = bpy.data.volumes.new("Cloud")
    vol.filepath = str(vdb)
    vol.render.precision = "FULL"
    vol.render.clipping = 0.0
    vol.render.space = "OBJECT"
    vol.render.step_size = 0.0
    ob = bpy.data.objects.new("Cloud", vol)
    ob.location = at
    scene.collection.objects.link(ob)
    vol.materials.append(cv._cloud_material(sigma, lobes))
    ob.welkin_cloud.enabled = True
    ob.welkin_cloud.density_scale = sigma
    cam = scene.camera
    cam.location = camera
    cam.data.lens = lens_mm
    cam.data.clip_start, cam.data.clip_end = 0.1, 1e6
    cv.look_at(cam, at)
    bpy.context.view_layer.update()
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    cv.exact_cycles(scene, samples=samples, seed=seed, bounces=bounces)
    return scene, sun, ob


# The lighting test's scene (tests/blender/test_cycles_clouds_lighting.py; replayed outside
# Blender by bench/clouds/cycles_addon_saved.py): the cumulus written at 2.7 times, seen from
# the ground through a 150 mm lens, in two views (the sun's elevation, azimuth in degrees).
TEST_SIGMA = 0.04 / 2.7
TEST_SIZE, TEST_SAMPLES, TEST_BOUNCES, TEST_PATHS = (96, 64), 128, 256, 256
TEST_VIEWS = {"side": (30.0, 60.0), "backlit": (43.0, 3.0)}


def build_test_view(T, vdb, elevation_deg, azimuth_deg):
    """The lighting test's scene for one view, with Welkin's phase."""
    return build(
        T,
        vdb,
        sigma=TEST_SIGMA,
        lobes=WELKIN_LOBES,
        sun_elevation_deg=elevation_deg,
        sun_azimuth_deg=azimuth_deg,
        camera=(0.0, 0.0, 1.5),
        lens_mm=150.0,
        size=TEST_SIZE,
        samples=TEST_SAMPLES,
        bounces=TEST_BOUNCES,
    )


def update_sky(scene, sun, native, lamp="ground", at=CLOUD_AT):
    """Update Sky; lamp="cloud": the lamp set to the sun at the cloud's altitude (above;
    the altitude of `at`). Returns the lamp's RGB irradiance at the ground and at the cloud."""
    import welkin
    from welkin import sky_request
    from welkin.blender.sky import scene_sun

    bpy.ops.welkin.update_sky()
    request, _lamp, _w = scene_sun.request_for(scene, scene.world.welkin, None)
    atm = sky_request.build_atmosphere(request, native)
    s = tuple(request.sun_direction)
    e_ground = np.array(welkin.sun(atm, request.altitude_m, s).direct_irradiance_rgb)
    e_cloud = np.array(welkin.sun(atm, at[2], s).direct_irradiance_rgb)
    if lamp == "cloud":
        scene.world.welkin.sync_lamp = False
        sun.data.energy = float(e_cloud.max())
        sun.data.color = tuple(float(v) for v in e_cloud / e_cloud.max())
    return e_ground, e_cloud


@contextlib.contextmanager
def world_seen_from(scene, altitude_m):
    """While the block runs, Cycles' world is the add-on's sky seen from altitude_m above the
    camera's (the world's Origin Altitude raised, Update Sky run), as the sky around a cloud
    at that height is; then the camera's own again. A world texture is at infinity: every
    point of a volume sees the same sky, the one from the observer's altitude. For a cloud
    kilometres up that is the sky from the ground, brighter above and darker below than the
    sky the cloud itself sees (docs/validation.md, "Each cloud type against Cycles"). The
    engine's pass and the reference take the observer from the world's altitude: leave the
    block before them. A lamp set for the cloud (update_sky, lamp="cloud") is kept; a synced
    one follows the sun at the raised altitude."""
    world = scene.world.welkin
    ground = world.altitude_m
    world.altitude_m = ground + altitude_m
    bpy.ops.welkin.update_sky()
    try:
        yield
    finally:
        world.altitude_m = ground
        bpy.ops.welkin.update_sky()


def engine_pass(scene, native, lobes, air=True):
    """The engine's Welkin.Clouds (H, W, 4) for the scene camera."""
    from welkin.blender.engine import render_engine

    depsgraph = bpy.context.evaluated_depsgraph_get()
    desc = json.loads(render_engine.scene_description_json(scene, depsgraph, native))
    if lobes != WELKIN_LOBES:
        ((g, _w),) = lobes
        desc["clouds"]["scattering"] = {"albedo": 1.0, "g_forward": g, "g_back": 0.0, "w_forward": 1.0}
    if not air:
        desc.setdefault("aerial", {})["sky_depth_m"] = 1.0
    return native.cloud_passes(native.SceneDescription.from_json_string(json.dumps(desc)))["Welkin.Clouds"]


def reference(scene, native, vdb, sigma, lobes, paths, seed=1, at=CLOUD_AT):
    """Welkin's path tracer for the scene camera's pixel rays under the atmosphere's light,
    the VDB placed at `at` as build() places it: (H, W, 3) RGB (the engine's conversion)
    and (H, W) transmittance."""
    import welkin
    from welkin import sky_request
    from welkin.blender import compat
    from welkin.blender.sky import scene_sun

    request, _lamp, _w = scene_sun.request_for(scene, scene.world.welkin, None)
    atm = sky_request.build_atmosphere(request, native)
    origin, dirs = cv.camera_rays(scene)
    mw = np.eye(4)
    mw[:3, 3] = np.array(at) - np.array(origin)  # cloud_radiance's observer is at its origin
    clouds = welkin.VdbClouds(
        str(vdb), density_scale=sigma, matrix_world=mw, placement=compat.cycles_vdb_placement()
    )
    phase = {} if lobes == WELKIN_LOBES else dict(g_forward=lobes[0][0], w_forward=1.0)
    L, T, _ = welkin.cloud_radiance(
        clouds,
        atm,
        request.altitude_m,
        tuple(request.sun_direction),
        dirs,
        method="reference",
        paths=paths,
        seed=seed,
        **phase,
    )
    rgb = welkin.spectrum_to_rgb(L, list(atm.wavelengths_nm), -3.0)
    r = scene.render
    return np.asarray(rgb).reshape(r.resolution_y, r.resolution_x, 3), np.asarray(T).reshape(
        r.resolution_y, r.resolution_x
    )


def luminance(x):
    return np.asarray(x)[..., :3] @ LUMINANCE


def regions(scene, alpha, sun_direction):
    """cloud_regions.image_regions of the scene camera's image: the sun's direction
    projected on the camera's right and up axes."""
    m = np.array(scene.camera.matrix_world.to_3x3())
    s = np.asarray(sun_direction, dtype=float)
    return image_regions(alpha, float(s @ m[:, 0]), float(s @ m[:, 1]))


def ratios(x, ref, regs):
    """Sum of luminance of x over that of ref, per region; and the per-pixel ratio's 10th,
    50th and 90th percentiles over "all"."""
    a, b = luminance(x), luminance(ref)
    out = {k: float(a[m].sum() / b[m].sum()) for k, m in regs.items() if m.any()}
    q = a[regs["all"]] / np.maximum(b[regs["all"]], 1e-12)
    for p in (10, 50, 90):
        out[f"p{p}"] = float(np.percentile(q, p))
    return out


def edge_over_core(x, regs, alpha):
    """The silver lining: the edge pixels' own brightness (luminance / alpha, the cloud's
    radiance without the premultiplication) over the core's, means over each region."""
    a = luminance(x) / np.maximum(alpha, 1e-6)
    return float(a[regs["edge"]].mean() / a[regs["core"]].mean())


def sun_direction(elevation_deg, azimuth_deg):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))
