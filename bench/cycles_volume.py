# SPDX-License-Identifier: Apache-2.0
"""One VDB cloud, rendered by Cycles and by Welkin for the same camera rays and the same light.

Used inside Blender (bench/cycles_clouds.py, tests/blender/test_cycles_clouds.py). What is
matched, and why it is the same problem for both renderers:

* Density: the .vdb is written here with pyopenvdb (vdb_dense.py; a FloatGrid `density`, values in [0, 1],
  compact support so that Cycles' clipping of near-zero voxels cuts nothing); both read the
  same file with its own transform and an identity matrix_world (Blender unit scale 1, so a
  Blender unit is a metre). sigma_t = density_scale x value, m^-1, in both: in Cycles the
  grid's value (Volume Info > Density) times density_scale feeds the scatter nodes' Density
  (Cycles' volume density is extinction per Blender unit), precision FULL (not half floats).
  Cycles 3.4 places a voxel's value half a voxel off OpenVDB's convention (value i at
  index i, which Welkin follows): at (i + 1/2) voxel along each axis (measured: Cycles'
  opacity against Welkin's differs by up to 0.22 at the cloud's edges unshifted, 0.35 and
  0.09, the noise, with Welkin's copy moved by -1/2 and +1/2 voxel). That +1/2 is Welkin's
  default placement="blender" (include/welkin/clouds/vdb.hpp), which welkin_render uses
  unless told placement="openvdb", so both render the same density.
* Albedo 1 and the phase: one Henyey-Greenstein lobe of eccentricity G (Cycles' Volume
  Scatter anisotropy is HG's g, positive forward, as Welkin's), Welkin's CloudPhase set to
  w_forward = 1, g_forward = G. Not Welkin's default two lobes: in Cycles 3.4 two Volume
  Scatter closures added (or mixed) are lit as the SUM of their normalised lobes, not the
  mixture weighted by their densities (measured with write_ball, optically thin, sun only:
  HG(0.8) alone and HG(-0.3) alone match the single-scattering closed form, 0.8 HG(0.8) +
  0.2 HG(-0.3) comes out 4.2 x the mixture = 0.91 x HG(0.8) + HG(-0.3), two identical
  half-density lobes 2 x), so a mixture cannot be matched there.
* Light: a sun lamp of strength E (Cycles: irradiance at normal incidence, W m^-2), angle 0
  (a delta, as Welkin's), and a world of uniform colour L (radiance, W m^-2 sr^-1) from every
  direction; Welkin gets the same through cloud_radiance(sun_irradiance=[E],
  ambient_radiance=[L]). One grey channel: Cycles' R = G = B.
* What is compared: Welkin's L is the cloud's in-scattered radiance, premultiplied, without
  the background; Cycles with film_transparent gives exactly that in RGB (the world seen
  straight through the cloud goes to alpha = 1 - T instead). Cycles' pixel filter is shrunk
  to 0.01 px so that a pixel is its centre's ray, the ray Welkin traces.
* Cycles' path length: max_bounces = volume_bounces = `bounces`, no clamping, no denoising,
  no adaptive sampling; heterogeneous volumes are ray-marched by Cycles (step_rate x voxel),
  which is Cycles' one approximation here.
"""

import math
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

# The one HG lobe of both renderers: near the mean cosine of Welkin's default CloudPhase
# (0.8 x 0.8 + 0.2 x -0.3 = 0.58).
G = 0.6


def write_cumulus(path, voxel_m=6.0, radius_m=220.0, seed=3):
    """A cumulus-like heap: a flat-bottomed union of smooth balls, density in [0, 1].

    Each ball contributes (1 - (r/R)^2)^2 inside R (compact support, smooth to first order),
    the union's value is the sum clipped to 1, below the base plane z < base it is faded out
    over 30 m (a flat cloud base). About radius_m across, centre at the origin."""
    rng = np.random.default_rng(seed)
    balls = [((0.0, 0.0, 0.0), 0.55 * radius_m)]
    for _ in range(9):
        az = rng.uniform(0, 2 * math.pi)
        rr = rng.uniform(0.25, 0.6) * radius_m
        c = (rr * math.cos(az), rr * math.sin(az), rng.uniform(-0.15, 0.35) * radius_m)
        balls.append((c, rng.uniform(0.3, 0.45) * radius_m))
    base = -0.3 * radius_m
    n = int(math.ceil(radius_m * 1.2 / voxel_m))
    ax = np.arange(-n, n + 1) * voxel_m
    x, y, z = np.meshgrid(ax, ax, ax, indexing="ij")
    d = np.zeros_like(x)
    for (cx, cy, cz), r in balls:
        q = ((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (r * r)
        d += np.where(q < 1.0, (1.0 - q) ** 2, 0.0)
    d = np.minimum(d * 1.5, 1.0)
    d *= np.clip((z - base) / 30.0, 0.0, 1.0)
    _write_dense(path, d.astype(np.float32), n, voxel_m)
    return voxel_m


def write_ball(path, voxel_m=10.0, radius_m=100.0):
    """A ball of constant density 1 (the test's case: no ray-marching error in Cycles
    beyond the boundary voxels)."""
    n = int(math.ceil(radius_m / voxel_m)) + 1
    ax = np.arange(-n, n + 1) * voxel_m
    x, y, z = np.meshgrid(ax, ax, ax, indexing="ij")
    d = (x * x + y * y + z * z <= radius_m * radius_m).astype(np.float32)
    _write_dense(path, d, n, voxel_m)
    return voxel_m


def _write_dense(path, d, n, voxel_m):
    # pyopenvdb, in this Python or in Debian's (vdb_dense.py).
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from vdb_dense import write_density

    write_density(path, d, (-n, -n, -n), voxel_m, tolerance=0.0, prune=True)


def look_at(obj, target):
    d = Vector(target) - obj.location
    obj.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()


def build_scene(
    vdb_path,
    *,
    density_scale,
    sun_direction,
    sun_irradiance,
    sky_radiance,
    camera_location,
    camera_target,
    width,
    height,
    samples,
    bounces=1024,
    step_rate=1.0,
    seed=0,
    lens_mm=50.0,
    lobes=((G, 1.0),),
):
    """Replaces the current scene's objects with the VDB volume, a sun lamp, a camera and a
    uniform world, all set for the comparison above. Returns the scene."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    scene = bpy.context.scene
    scene.unit_settings.scale_length = 1.0

    vol = bpy.data.volumes.new("Cloud")
    vol.filepath = str(vdb_path)
    vol.render.precision = "FULL"
    vol.render.clipping = 0.0
    vol.render.space = "OBJECT"
    vol.render.step_size = 0.0  # automatic: the voxel size times Cycles' step rate
    vol_obj = bpy.data.objects.new("Cloud", vol)
    scene.collection.objects.link(vol_obj)
    vol_obj.data.materials.append(_cloud_material(density_scale, lobes))

    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = float(sun_irradiance)
    sun.data.color = (1.0, 1.0, 1.0)
    sun.data.angle = 0.0
    s = Vector(sun_direction).normalized()
    sun.rotation_euler = s.to_track_quat("Z", "Y").to_euler()  # a sun lamp shines along its -Z
    scene.collection.objects.link(sun)

    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.lens = lens_mm
    cam.data.clip_start, cam.data.clip_end = 0.1, 1e6  # Cycles stops camera rays at clip_end
    cam.data.sensor_fit = "AUTO"
    cam.location = camera_location
    look_at(cam, camera_target)
    scene.collection.objects.link(cam)
    scene.camera = cam

    world = bpy.data.worlds.new("Uniform")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bg.inputs["Strength"].default_value = float(sky_radiance)
    scene.world = world

    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.threads_mode = "FIXED"
    r.threads = os.cpu_count() or 2
    r.use_persistent_data = False
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    exact_cycles(scene, samples=samples, seed=seed, bounces=bounces)
    c = scene.cycles
    c.volume_step_rate = float(step_rate)
    c.use_auto_tile = False
    return scene


def exact_cycles(scene, *, samples, seed, bounces):
    """The Cycles settings of the cloud comparisons: the CPU, `samples` per pixel at `seed`
    (no adaptive sampling, denoising or clamping), `bounces` volume bounces and no others,
    film_transparent (RGB the cloud's premultiplied radiance, A = 1 - T), each pixel its
    centre's ray, a linear 32-bit RGBA EXR."""
    r = scene.render
    r.engine = "CYCLES"
    r.film_transparent = True
    r.filter_size = 0.01
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_mode = "RGBA"
    r.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    c = scene.cycles
    c.device = "CPU"
    c.samples = int(samples)
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = int(seed)
    c.max_bounces = c.volume_bounces = c.transparent_max_bounces = int(bounces)
    c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 0
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.volume_max_steps = 4096
    # The pixel centre's ray: a Gaussian 0.01 px wide (Cycles' box filter is one pixel wide
    # whatever filter_width says: docs/validation.md, "Cycles' pixel filter").
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01


def _cloud_material(density_scale, lobes):
    m = bpy.data.materials.new("CloudPhase")
    m.use_nodes = True
    nodes, links = m.node_tree.nodes, m.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    info = nodes.new("ShaderNodeVolumeInfo")
    add = nodes.new("ShaderNodeAddShader")
    for i, (g, w) in enumerate(lobes):
        mul = nodes.new("ShaderNodeMath")
        mul.operation = "MULTIPLY"
        mul.inputs[1].default_value = float(density_scale) * w
        links.new(info.outputs["Density"], mul.inputs[0])
        sc = nodes.new("ShaderNodeVolumeScatter")
        sc.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        sc.inputs["Anisotropy"].default_value = g
        links.new(mul.outputs[0], sc.inputs["Density"])
        links.new(sc.outputs[0], add.inputs[i])
    links.new(add.outputs[0], out.inputs["Volume"])
    return m


def camera_rays(scene):
    """The camera's origin and the unit direction through each pixel's centre, (H*W, 3),
    rows top first, from Blender's own view frame (Camera.view_frame: the frame's corners
    in camera space), in world space."""
    cam = scene.camera
    r = scene.render
    w = r.resolution_x * r.resolution_percentage // 100
    h = r.resolution_y * r.resolution_percentage // 100
    frame = [tuple(v) for v in cam.data.view_frame(scene=scene)]
    xs = [v[0] for v in frame]
    ys = [v[1] for v in frame]
    zc = frame[0][2]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    u = x0 + (np.arange(w) + 0.5) / w * (x1 - x0)
    v = y1 - (np.arange(h) + 0.5) / h * (y1 - y0)
    uu, vv = np.meshgrid(u, v)
    d = np.stack([uu, vv, np.full_like(uu, zc)], axis=-1).reshape(-1, 3)
    rot = np.array(cam.matrix_world.to_3x3())
    d = d @ rot.T
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return tuple(cam.matrix_world.translation), d


def render(scene, path):
    """Renders the scene with Cycles to `path` (EXR) and returns (H, W, 4) float32, rows top
    first (RGB premultiplied, A = 1 - T)."""
    import welkin

    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    pixels, names = welkin.read_exr(str(path))
    return np.stack([pixels[..., names.index(c)] for c in "RGBA"], axis=-1)


def welkin_render(
    scene,
    vdb_path,
    density_scale,
    sun_direction,
    sun_irradiance,
    sky_radiance,
    method,
    placement="blender",
    **kw,
):
    """Welkin's cloud_radiance for the scene camera's pixel rays: (H, W) radiance and
    transmittance, rows top first; the voxels placed by `placement` (VdbClouds' default,
    "blender", is where Cycles 3.4 renders them)."""
    import welkin

    r = scene.render
    h, w = r.resolution_y, r.resolution_x
    origin, dirs = camera_rays(scene)
    clouds = welkin.VdbClouds(
        str(vdb_path), density_scale=density_scale, matrix_world=np.eye(4), placement=placement
    )
    atm = welkin.Atmosphere.preset("bruneton2017")  # does not light the cloud here
    L, T, _ = welkin.cloud_radiance(
        clouds,
        atm,
        0.0,
        tuple(sun_direction),
        dirs,
        origin=origin,
        method=method,
        sun_irradiance=[float(sun_irradiance)],
        ambient_radiance=[float(sky_radiance)],
        g_forward=G,
        w_forward=1.0,
        **kw,
    )
    return L[:, 0].reshape(h, w), T.reshape(h, w)
