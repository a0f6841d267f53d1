# SPDX-License-Identifier: Apache-2.0
"""Each procedural cloud type as a VDB patch under the add-on's own sky, rendered by Cycles
and by Welkin for the same pixels (used by bench/clouds/cycles_types_lighting.py and
tests/blender/test_cycles_cloud_types.py; inside Blender, the add-on installed). The
scene, the light and what each renderer gets are bench/cycles_addon_clouds.py's (its
helpers, imported); what is new is the cloud:

* The layer: welkin.CloudLayer(cloud_type=...) at the type's preset (altitudes, coverage,
  density, scales; seed 1, no wind), on the curved planet with the world origin on the
  ground.
* The patch: a square of PATCH_M on a side around the layer's densest column, found by a
  rule, not by coordinates (so that a change of the shapes moves the patch with its
  cloud): the vertical optical depth of columns SEARCH_STEP_M apart over a SEARCH_M square
  around the origin, box-averaged over a quarter of the patch, and the largest taken.
* Its density: the layer's own sigma_t (CloudDensity.sigma_t, the core's density
  function), sampled at the voxels' centres in the layer's altitude frame (each voxel at
  its altitude above the curved ground, so the patch's base is flat as the shell is
  locally), the whole layer's height and a voxel of air above and below. A window takes it
  to 0 over the outer PATCH_TAPER of each half-width (a raised cosine in x and in y), so
  that the patch is a cloud with soft sides, not a block cut out of a deck; both renderers
  get that same windowed density. Written as a FloatGrid `density` in [0, 1] (the patch's
  largest sigma_t is its density_scale), with pyopenvdb (bench/vdb_dense.py).
* The view: the camera on the ground, CAMERA_DISTANCE patch widths from the patch's centre
  along +X, aimed at it, its lens framing the patch's near side with a margin; "side": the
  sun 30 degrees up, 60 degrees left of the view (the VDB cumulus's); "backlit": the sun
  3 degrees right of the view and BACKLIT_ABOVE_DEG above the patch's near top edge as the
  camera sees it (the silver lining).

What this compares is the lighting of the same density: the layer's density at the
patch's voxels, through each renderer's VDB path. It does not render the layer through
Welkin's own procedural path (its baked noise and depth grids, the march's level of
detail), nor the layer's extent beyond the patch (the neighbouring clouds' shadows and
light).
"""

import contextlib
import importlib.util
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vdb_dense import write_density  # noqa: E402

# The patch (write_patch) is written without Blender; the comparison needs it.
if importlib.util.find_spec("bpy") is not None:
    import bpy
    import cycles_addon_clouds as ac
    import cycles_volume as cv

PATCH_M = 3000.0
PATCH_TAPER = 0.3
SEARCH_M = 24000.0
SEARCH_STEP_M = 250.0
CAMERA_DISTANCE = 2.2
CAMERA_Z = 1.5
BACKLIT_ABOVE_DEG = 3.0
SIDE_SUN = (30.0, 60.0)
REGIONS = ("all", "sunlit", "shadow", "base")


def _window(t):
    """1 for |t| <= 1 - PATCH_TAPER, a raised cosine down to 0 at |t| = 1."""
    u = np.clip((np.abs(t) - (1.0 - PATCH_TAPER)) / PATCH_TAPER, 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(math.pi * u))


def _points(x, y, altitude, planet_radius_m):
    """World points (the origin on the ground) at horizontal x, y and `altitude` above
    the curved ground."""
    r = planet_radius_m
    z = np.sqrt((r + altitude) ** 2 - x * x - y * y) - r
    return np.stack([x, y, z], axis=-1).reshape(-1, 3)


def densest_column(layer, planet_radius_m=6360e3, steps=24):
    """(x, y) of the patch's centre (the module's rule) and the vertical optical depth
    there, box-averaged."""
    ax = np.arange(-SEARCH_M / 2, SEARCH_M / 2 + 1.0, SEARCH_STEP_M)
    dz = (layer.top_altitude_m - layer.bottom_altitude_m) / steps
    h = layer.bottom_altitude_m + (np.arange(steps) + 0.5) * dz
    x, y, hh = np.meshgrid(ax, ax, h, indexing="ij")
    sig = np.asarray(layer.sigma_t(_points(x, y, hh, planet_radius_m))).reshape(x.shape)
    tau = sig.sum(axis=2) * dz
    k = max(1, int(round(PATCH_M / 4 / SEARCH_STEP_M)))
    c = np.cumsum(np.cumsum(np.pad(tau, ((1, 0), (1, 0))), axis=0), axis=1)
    box = (c[k:, k:] - c[:-k, k:] - c[k:, :-k] + c[:-k, :-k]) / (k * k)  # mean over k x k
    i, j = np.unravel_index(int(np.argmax(box)), box.shape)
    cx = 0.5 * (ax[i] + ax[i + k - 1])
    cy = 0.5 * (ax[j] + ax[j + k - 1])
    return float(cx), float(cy), float(box[i, j])


class Patch:
    """A written patch: path, density_scale (m^-1), `at` (where build() puts the grid's
    origin: the patch's centre, its z the altitude of a voxel plane), the layer's bottom
    and top, the column (x, y) it was cut around and its box-averaged optical depth."""

    def __init__(self, **kw):
        self.__dict__.update(kw)


def write_patch(native, cloud_type, path, voxel_m, planet_radius_m=6360e3):
    layer = native.CloudLayer(cloud_type=cloud_type)
    cx, cy, tau = densest_column(layer, planet_radius_m)
    n = int(math.ceil(PATCH_M / 2 / voxel_m))
    ax = np.arange(-n, n + 1) * voxel_m
    k0 = int(math.floor(layer.bottom_altitude_m / voxel_m)) - 1
    k1 = int(math.ceil(layer.top_altitude_m / voxel_m)) + 1
    h = np.arange(k0, k1 + 1) * voxel_m
    x, y, hh = np.meshgrid(cx + ax, cy + ax, h, indexing="ij")
    sig = np.asarray(layer.sigma_t(_points(x, y, hh, planet_radius_m))).reshape(x.shape)
    w = _window(ax / (n * voxel_m))
    sig = sig * w[:, None, None] * w[None, :, None]
    scale = float(sig.max())
    if not scale > 0.0:
        raise RuntimeError(f"{cloud_type}: the patch around ({cx:.0f}, {cy:.0f}) m is empty")
    kc = (k0 + k1) // 2
    write_density(
        path, (sig / scale).astype(np.float32), (-n, -n, k0 - kc), voxel_m, tolerance=0.0, prune=True
    )
    distance = CAMERA_DISTANCE * PATCH_M
    return Patch(
        path=str(path),
        cloud_type=cloud_type,
        density_scale=scale,
        at=(distance, 0.0, kc * voxel_m),
        bottom_m=layer.bottom_altitude_m,
        top_m=layer.top_altitude_m,
        column=(cx, cy),
        column_tau=tau,
        voxel_m=voxel_m,
        shape=sig.shape,
    )


def lens_mm(sensor_mm=36.0):
    """The horizontal field framing the patch's near side (half a width closer) with a
    10 % margin each way."""
    half = 0.55 * PATCH_M / ((CAMERA_DISTANCE - 0.5) * PATCH_M)
    return 0.5 * sensor_mm / half


def sun_for(patch, view):
    """(elevation, azimuth) of the sun in degrees for a view of the patch."""
    if view == "side":
        return SIDE_SUN
    near = (CAMERA_DISTANCE - 0.5) * PATCH_M
    return math.degrees(math.atan2(patch.top_m - CAMERA_Z, near)) + BACKLIT_ABOVE_DEG, 3.0


def lining_regions(alpha):
    """The silver lining's edge and core pixels by the opacity `alpha`, relative to the
    cloud's own: with q the 99th percentile of alpha over the cloud's pixels (alpha > 0.05;
    q at most 1), the core is alpha > 0.95 q and the edge 0.05 < alpha < 0.6 q. A dense
    cloud (q = 1) keeps ac.regions' edge and core; a thin one (cirrus, whose alpha stays
    well under 0.95) gets its own."""
    cloud = alpha > 0.05
    if not cloud.any():
        return {"edge": cloud, "core": cloud}
    q = min(1.0, float(np.percentile(alpha[cloud], 99)))
    return {"edge": cloud & (alpha < 0.6 * q), "core": cloud & (alpha > 0.95 * q)}


def edge_over_core(x, regs, alpha):
    """ac.edge_over_core over regs (lining_regions), None where the view has no edge or no
    core pixels."""
    if not regs["edge"].any() or not regs["core"].any():
        return None
    return ac.edge_over_core(x, regs, alpha)


def build(T, native, patch, *, size, samples, bounces):
    """bench/cycles_addon_clouds.py's scene for the patch (the sun of the "side" view), with
    Cycles' persistent data on: the volume, whose loading is most of a small render's time,
    is synced once for every seed and view of the patch. Returns (scene, sun lamp)."""
    el, az = sun_for(patch, "side")
    scene, sun, _ob = ac.build(
        T,
        patch.path,
        sigma=patch.density_scale,
        lobes=ac.WELKIN_LOBES,
        sun_elevation_deg=el,
        sun_azimuth_deg=az,
        camera=(0.0, 0.0, CAMERA_Z),
        lens_mm=lens_mm(),
        size=size,
        samples=samples,
        bounces=bounces,
        at=patch.at,
    )
    scene.render.use_persistent_data = True
    return scene, sun


def compare(
    T, native, patch, built, view, *, paths, samples=None, seeds=(1, 2), tmp, log=print, world_at_cloud=False
):
    """One view of a patch in the scene build() made: the sun aimed and Update Sky run (the
    lamp at the cloud's altitude), Cycles once per seed (`samples` each, else build()'s),
    the engine's pass (the fast march, the air left out) and, with paths, the reference
    once per seed. Returns a dict: the ratios to Cycles' seed mean per region ("fast",
    "reference"), their noise (half the difference between the seeds' ratios:
    "fast_noise", "reference_noise"), the edge-over-core of each renderer, its luminance
    over the fast march's opacity ("lining": {"cycles", "cycles_noise", "fast",
    "reference"}), the cloud's pixel count ("pixels") and Cycles' and the fast march's mean
    alpha over them ("alpha", "fast_alpha"). world_at_cloud: Cycles' world is the sky seen
    from the patch's altitude (the world's Origin Altitude), not from the ground; the fast
    march and the reference, which light the cloud with the sky at its own altitude
    whatever the world shows, are unchanged."""
    scene, sun = built
    if samples:
        scene.cycles.samples = samples
    el, az = sun_for(patch, view)
    T.aim_sun(sun, el, az)
    bpy.context.view_layer.update()
    ac.update_sky(scene, sun, native, lamp="cloud", at=patch.at)
    cyc = []
    with ac.world_seen_from(scene, patch.at[2]) if world_at_cloud else contextlib.nullcontext():
        for seed in seeds:
            scene.cycles.seed = seed
            cyc.append(cv.render(scene, os.path.join(tmp, f"cycles_{patch.cloud_type}_{view}_{seed}.exr")))
    c = sum(cyc) / len(cyc)
    fast = ac.engine_pass(scene, native, ac.WELKIN_LOBES, air=False)
    refs = []
    for seed in seeds if paths else ():
        rgb, t = ac.reference(
            scene, native, patch.path, patch.density_scale, ac.WELKIN_LOBES, paths, seed, patch.at
        )
        refs.append(np.concatenate([rgb, (1.0 - t)[..., None]], axis=-1))
    regs = ac.regions(scene, c[..., 3], ac.sun_direction(el, az))
    out = {
        "pixels": int(regs["all"].sum()),
        "alpha": float(c[..., 3][regs["all"]].mean()) if regs["all"].any() else 0.0,
    }
    if not regs["all"].any():
        return out

    def noise(pairs):
        r = [ac.ratios(x, y, regs) for x, y in pairs]
        return {k: abs(r[0][k] - r[-1][k]) / 2 for k in r[0]}

    out["fast_alpha"] = float(fast[..., 3][regs["all"]].mean())
    out["fast"] = ac.ratios(fast, c, regs)
    out["fast_noise"] = noise([(fast, y) for y in cyc])
    if refs:
        out["reference"] = ac.ratios(sum(refs) / len(refs), c, regs)
        out["reference_noise"] = noise(list(zip(refs, cyc)))
    # The lining: every renderer's luminance over one opacity, the fast march's 1 - T (the
    # path tracer's ratio tracking agrees within 4 % at the thinnest pixels, and no seed's
    # noise picks the pixels). Cycles' film alpha is no transmittance there: at the pixels
    # thinner than 0.03 it reads up to 3.5 times the opacity both of Welkin's estimators
    # agree on while its luminance there agrees with theirs, and divided by it Cycles' own
    # edge came out dim (docs/validation.md, "Cycles' alpha at a cloud's thin edge").
    opacity = fast[..., 3]
    lregs = lining_regions(opacity)
    ln = [edge_over_core(y, lregs, opacity) for y in cyc]
    out["lining"] = {
        "cycles": edge_over_core(c, lregs, opacity),
        "cycles_noise": abs(ln[0] - ln[-1]) / 2 if None not in ln else None,
        "fast": edge_over_core(fast, lregs, opacity),
        "reference": edge_over_core(sum(refs) / len(refs), lregs, opacity) if refs else None,
    }
    log(
        f"{patch.cloud_type} {view}: sun {el:.1f} / {az:.1f} deg, {out['pixels']} cloud pixels, "
        f"Cycles' mean alpha {out['alpha']:.3f}; "
        + "; ".join(
            f"{k} / Cycles "
            + ", ".join(f"{r} {out[k][r]:.3f} (+-{out[k + '_noise'][r]:.3f})" for r in REGIONS if r in out[k])
            for k in ("fast", "reference")
            if k in out
        )
        + "; edge over core "
        + ", ".join(f"{k} {v:.3f}" for k, v in out["lining"].items() if v is not None)
    )
    return out
