# SPDX-License-Identifier: Apache-2.0
"""Welkin beside Blender 5.0's own sky textures, "Multiple Scattering" and "Single
Scattering" (Nishita's model), at the same sun: zenith, horizon ring and upper-hemisphere
mean (green channel, linear Rec.709 W m^-2 sr^-1), and the time each takes to prepare.

    PYTHONPATH=build build/venv-bpy-5.0/bin/python bench/blender5_sky_peer.py [--docs]

(PyPI's bpy 5.0 as the Python; the compiled module from build/ on PYTHONPATH; the add-on
need not be installed: the version shims come from the source tree's
addon/welkin/blender/compat.py, which needs bpy alone. Blender 5.1 and later run Python
3.13: PYTHONPATH=<a folder with the cp313 wheel's module> and build/venv-bpy-5.3/bin/python
compare with that Blender's skies.) Prints a markdown table, writes
bench/results/blender5_sky_peer.csv (--csv PATH: elsewhere), and with --docs puts the table
into docs/validation.md between its "blender5-sky-peer" markers. --quick: one sun elevation
(--elevation), 32 x 16 pixels, one sample and one repeat: a check that it runs, not a
measurement.

Radiance: each Blender sky is rendered by Cycles through an equirectangular panoramic
camera at 256 x 128, 16 samples at the pixel centres (a 0.01-pixel filter), its default
air, dust and ozone, no sun disc; Welkin is welkin.sky_image at 256 x 128 (the add-on's
`auto` method, bruneton2017 preset, observer at 0 m, no disc): the same pixel grid.
zenith: the mean of the top row; horizon ring: the mean of the row just above the horizon
(elevation 0-1.4 degrees); hemisphere mean: the solid-angle-weighted mean of the upper half.
Preparation: Blender's, the Cycles render of an 8 x 4 panorama after a change of the sun
(the sky texture is precomputed then) minus the same render with a constant world, median
of 3; Welkin's, welkin.sky_image at 1024 x 512 (the add-on's default world image, LUTs
included), median of 3.
"""

import argparse
import importlib.util
import math
import os
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "blender"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

ELEVATIONS = (60.0, 20.0, 5.0, 0.0, -4.0)
AZIMUTH = 0.0
W, H = 256, 128
_BLENDER = f"Blender {bpy.app.version[0]}.{bpy.app.version[1]}"
MODELS = (
    ("MULTIPLE_SCATTERING", f"{_BLENDER} Multiple Scattering"),
    ("SINGLE_SCATTERING", f"{_BLENDER} Single Scattering (Nishita)"),
)
BEGIN, END = "<!-- blender5-sky-peer:begin -->", "<!-- blender5-sky-peer:end -->"


def import_welkin():
    try:
        import welkin
    except ImportError as error:
        raise SystemExit(
            f"blender5_sky_peer: the compiled module is not on PYTHONPATH (PYTHONPATH=build): {error}"
        ) from None
    return welkin


def source_compat():
    """addon/welkin/blender/compat.py of this tree, by path: `welkin` on PYTHONPATH=build is
    the compiled module, not the add-on's package."""
    spec = importlib.util.spec_from_file_location(
        "welkin_source_compat", ROOT / "addon" / "welkin" / "blender" / "compat.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def setup(scene, width, height, samples):
    import addon_testing as T

    if scene.camera is None:
        cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
        scene.collection.objects.link(cam)
        scene.camera = cam
    T.panoramic_camera(scene, width, height, samples=samples, compat=source_compat())


def sky_world(sky_type):
    world = bpy.data.worlds.new(sky_type)
    tree = world.node_tree  # 5.0+: every world has its tree and uses it
    node = tree.nodes.new("ShaderNodeTexSky")
    node.sky_type = sky_type
    node.sun_disc = False
    node.sun_rotation = math.radians((90.0 - AZIMUTH) % 360.0)  # sun at 90 deg - rotation
    background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    tree.links.new(node.outputs["Color"], background.inputs["Color"])
    return world, node


def render(scene, path):
    scene.render.filepath = str(path)
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - t0


def read(welkin, path):
    pixels, names = welkin.read_exr(str(path))
    return np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)


def stats(img):
    g = img[..., 1].astype(np.float64)
    h = g.shape[0]
    cos_e = np.cos(math.pi * (0.5 - (np.arange(h // 2) + 0.5) / h))
    return {
        "zenith": float(g[0].mean()),
        "horizon ring": float(g[h // 2 - 1].mean()),
        "hemisphere mean": float((g[: h // 2].mean(axis=1) * cos_e).sum() / cos_e.sum()),
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--docs", action="store_true", help="write the table into docs/validation.md")
    parser.add_argument(
        "--csv", type=pathlib.Path, default=ROOT / "bench" / "results" / "blender5_sky_peer.csv"
    )
    parser.add_argument("--quick", action="store_true", help="a run that checks the script")
    parser.add_argument("--elevation", type=float, default=20.0, help="--quick's sun, degrees")
    args = parser.parse_args(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:])
    welkin = import_welkin()
    if bpy.app.version < (5, 0, 0):
        raise SystemExit(
            f"blender5_sky_peer: needs the bpy of Blender 5.0 or later, this is {bpy.app.version_string}"
        )
    import atexit
    import shutil
    import tempfile

    tmp = pathlib.Path(tempfile.mkdtemp(prefix="welkin_peer_"))
    atexit.register(shutil.rmtree, tmp, ignore_errors=True)
    scene = bpy.context.scene
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    atm = welkin.Atmosphere.preset("bruneton2017")
    method = "auto" if "auto" in welkin.methods() else "lut"
    if args.quick and args.docs:
        raise SystemExit("blender5_sky_peer: --quick measures nothing to put into the docs")
    elevations, (w, h, samples, repeats, prep_width) = (
        ((args.elevation,), (32, 16, 1, 1, 64)) if args.quick else (ELEVATIONS, (W, H, 16, 3, 1024))
    )

    rows = []
    for e in elevations:
        s = (
            math.cos(math.radians(e)) * math.cos(math.radians(AZIMUTH)),
            math.cos(math.radians(e)) * math.sin(math.radians(AZIMUTH)),
            math.sin(math.radians(e)),
        )
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            welkin.sky_image(atm, 0.0, s, prep_width, method, sun_disc=False)
            times.append(time.perf_counter() - t0)
        ours = welkin.sky_image(atm, 0.0, s, w, method, sun_disc=False)
        rows.append((e, f"Welkin ({method})", stats(ours), statistics.median(times)))
        for sky_type, label in MODELS:
            world, node = sky_world(sky_type)
            node.sun_elevation = math.radians(e)
            scene.world = world
            setup(scene, w, h, samples)
            render(scene, tmp / "sky.exr")
            theirs = stats(read(welkin, tmp / "sky.exr"))
            # Preparation: tiny renders after a change of the sun, minus a constant world.
            setup(scene, 8, 4, 1)
            constant = bpy.data.worlds.new("Constant")
            prep = []
            for k in range(repeats):
                node.sun_elevation = math.radians(e + 0.01 * (k + 1))
                scene.world = world
                with_sky = render(scene, tmp / "small.exr")
                scene.world = constant
                prep.append(with_sky - render(scene, tmp / "small.exr"))
            rows.append((e, label, theirs, statistics.median(prep)))

    write_results(rows, args)


def write_results(rows, args):
    """Prints the table, writes the CSV and, with --docs, the table into docs/validation.md."""
    header = (
        "| sun | sky | zenith | horizon ring | hemisphere mean | Welkin / it: zenith, "
        "horizon, hemisphere | preparation |"
    )
    lines = [header, "|---|---|---|---|---|---|---|"]
    csv = ["sun_deg,sky,zenith,horizon_ring,hemisphere_mean,prepare_s"]
    for e, label, st, seconds in rows:
        ours = next(r[2] for r in rows if r[0] == e and r[1].startswith("Welkin"))
        ratio = (
            ""
            if label.startswith("Welkin")
            else ", ".join(f"{ours[k] / st[k]:.2f}" if st[k] > 0 else "-" for k in st)
        )
        lines.append(
            f"| {e:g}° | {label} | {st['zenith']:.4g} | {st['horizon ring']:.4g} | "
            f"{st['hemisphere mean']:.4g} | {ratio} | {seconds * 1000:.0f} ms |"
        )
        csv.append(
            f"{e},{label},{st['zenith']:.6g},{st['horizon ring']:.6g},"
            f"{st['hemisphere mean']:.6g},{seconds:.4f}"
        )
    note = (
        f"Blender {bpy.app.version_string} (PyPI bpy), {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.1f}; green channel, W m^-2 sr^-1"
    )
    table = "\n".join(lines)
    print(f"\n{note}\n\n{table}")
    out = args.csv
    out.write_text("\n".join(csv) + "\n")
    print(f"\nwritten: {out}")
    if args.docs:
        doc = ROOT / "docs" / "validation.md"
        text = doc.read_text()
        if BEGIN not in text or END not in text:
            raise SystemExit(f"blender5_sky_peer: no {BEGIN} ... {END} markers in {doc}")
        head, rest = text.split(BEGIN, 1)
        _old, tail = rest.split(END, 1)
        doc.write_text(f"{head}{BEGIN}\n{note}:\n\n{table}\n{END}{tail}")
        print(f"written: {doc}")


main()
