# SPDX-License-Identifier: Apache-2.0
"""A time-of-day contact sheet: Welkin beside Blender's own skies, sun 60, 20, 5, 1, -2, -6
and -12 degrees, one row each, the same camera and exposure across a row.

    blender -b --factory-startup --python-use-system-env --python bench/time_of_day_sheet.py \
        [-- --out docs/time_of_day.png]

Skies: Welkin (the add-on's world as a user gets it: the default `auto` sky at 1024 x 512
and the sun's disc drawn by the world's nodes), Blender's Nishita sky (this Blender), and
Blender 5's "Multiple Scattering" sky in the newest PyPI bpy of build/venv-bpy-5.3 .. 5.0
that is there (the newest Blender the tests run): this script runs itself in that Python
(--blender5 DIR) to render that sky. Each sky has two columns, looking toward the sun and
away from it (where a clear sky is bluest). Every tile is a Cycles render through the same
equirectangular panoramic camera: 120 degrees of azimuth centred on the view's, elevation
-10 to +70 degrees; the Blender skies with their default air, dust and ozone and their sun
disc. Exposure: per row, one factor for all six columns (0.18 over Welkin's median sky
luminance in that row's two tiles, shown as EV); tone curve x / (1 + x) per
channel, then sRGB. --keep DIR keeps the linear tiles (<sky>_<sun>_<view>.exr), which
`bench/measured_sky_compare.py --sheet DIR` measures. The add-on is installed from its zip as in the tests
(a temporary scripts directory; the machine's Blender configuration is untouched).
"""

import argparse
import atexit
import math
import pathlib
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
ELEVATIONS = (60.0, 20.0, 5.0, 1.0, -2.0, -6.0, -12.0)
AZIMUTH = 0.0  # the sun towards +X
# (name, camera azimuth relative to the sun's, label)
VIEWS = (("toward", 0.0, "toward the sun"), ("away", 180.0, "away from the sun"))
TILE_W, TILE_H = 240, 160
LON_HALF, LAT_MIN, LAT_MAX = 60.0, -10.0, 70.0
SAMPLES = 32
# PyPI's bpy venvs (build/venv-bpy-<v>), newest first: the first present renders Blender 5's
# Multiple Scattering sky.
MULTIPLE_SCATTERING_VERSIONS = (
    "5.3",
    "5.2",
    "5.1",
    "5.0",
)  # the horizon is a hard edge inside a pixel row: fewer leave it speckled

import bpy  # noqa: E402


def aim_camera(scene, view_azimuth):
    scene.camera.rotation_euler = (math.radians(90.0), 0.0, math.radians(AZIMUTH + view_azimuth - 90.0))


def render_views(scene, out_dir, stem):
    """One render per view of VIEWS: <stem>_<view>.exr."""
    for view, view_azimuth, _label in VIEWS:
        aim_camera(scene, view_azimuth)
        scene.render.filepath = str(pathlib.Path(out_dir) / f"{stem}_{view}.exr")
        bpy.ops.render.render(write_still=True)


def setup_camera(scene):
    """An equirectangular crop, Cycles, linear EXR (aim_camera turns it)."""
    if scene.camera is None:
        cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
        scene.collection.objects.link(cam)
        scene.camera = cam
    cam = scene.camera
    cam.location = (0.0, 0.0, 0.0)
    cam.rotation_mode = "XYZ"
    aim_camera(scene, 0.0)
    cam.data.type = "PANO"
    pano = cam.data if hasattr(cam.data, "panorama_type") else cam.data.cycles
    pano.panorama_type = "EQUIRECTANGULAR"
    pano.longitude_min, pano.longitude_max = math.radians(-LON_HALF), math.radians(LON_HALF)
    pano.latitude_min, pano.latitude_max = math.radians(LAT_MIN), math.radians(LAT_MAX)
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = TILE_W, TILE_H
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGB"
    scene.view_settings.view_transform = "Standard"


def blender_sky_world(sky_type):
    world = bpy.data.worlds.new(sky_type.title())
    world.use_nodes = True
    tree = world.node_tree
    node = tree.nodes.new("ShaderNodeTexSky")
    node.sky_type = sky_type
    node.sun_disc = True
    # Blender's sky puts the sun at azimuth 90 degrees - sun_rotation from +X
    # (counter-clockwise; its rotation is kept within [0, 360) degrees).
    node.sun_rotation = math.radians((90.0 - AZIMUTH) % 360.0)
    background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    tree.links.new(node.outputs["Color"], background.inputs["Color"])
    return world, node


def render_blender_sky(scene, sky_type, out_dir, prefix):
    world, node = blender_sky_world(sky_type)
    scene.world = world
    for e in ELEVATIONS:
        node.sun_elevation = math.radians(e)
        render_views(scene, out_dir, f"{prefix}_{e:+05.1f}")


def blender5_main(out_dir):
    """Run in bpy 5.x's Python: the Multiple Scattering column."""
    scene = bpy.context.scene
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    setup_camera(scene)
    render_blender_sky(scene, "MULTIPLE_SCATTERING", out_dir, "multiple")


def read_exr(path):
    import numpy as np

    image = bpy.data.images.load(str(path))
    w, h = image.size
    flat = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(flat)
    bpy.data.images.remove(image)
    return flat.reshape(h, w, 4)[::-1, :, :3]


def main(out_png, keep=None):
    import numpy as np
    from PIL import Image, ImageDraw

    sys.path.insert(0, str(ROOT / "tests" / "blender"))
    import addon_testing as T

    T.install_addon()
    if keep is not None:
        tmp = pathlib.Path(keep)
        tmp.mkdir(parents=True, exist_ok=True)
    else:
        tmp = pathlib.Path(tempfile.mkdtemp(prefix="welkin_sheet_"))
        atexit.register(shutil.rmtree, tmp, ignore_errors=True)

    scene, sun = T.new_scene(ELEVATIONS[0], AZIMUTH, resolution="1024")
    setup_camera(scene)
    for e in ELEVATIONS:
        T.aim_sun(sun, e, AZIMUTH)
        bpy.context.view_layer.update()
        bpy.ops.welkin.update_sky()
        render_views(scene, tmp, f"welkin_{e:+05.1f}")
    version = bpy.app.version_string.split()[0]
    render_blender_sky(scene, "NISHITA", tmp, "nishita")
    columns = [("welkin", "Welkin (add-on world)"), ("nishita", f"Blender {version} Nishita")]

    # The newest Blender the tests run (scripts/test_blender.sh) draws the Multiple
    # Scattering column (the sky type exists from 5.0 on).
    newest = next(
        (
            v
            for v in MULTIPLE_SCATTERING_VERSIONS
            if (ROOT / "build" / f"venv-bpy-{v}" / "bin" / "python").exists()
        ),
        None,
    )
    if newest is not None:
        python5 = ROOT / "build" / f"venv-bpy-{newest}" / "bin" / "python"
        run = subprocess.run(
            [str(python5), str(pathlib.Path(__file__).resolve()), "--blender5", str(tmp)],
            capture_output=True,
            text=True,
        )
        if run.returncode == 0:
            columns.append(("multiple", f"Blender {newest} Multiple Scattering"))
        else:
            print(f"Blender {newest}'s sky not rendered (bpy {newest} failed):\n{run.stderr[-2000:]}")
    else:
        print("Blender 5's sky not rendered: no build/venv-bpy-5.x (scripts/install_blender_venvs.sh)")

    label_w, head_h = 92, 36
    tiles_per_row = [(key, view[0]) for key, _title in columns for view in VIEWS]
    sheet = Image.new(
        "RGB", (label_w + TILE_W * len(tiles_per_row), head_h + TILE_H * len(ELEVATIONS)), (24, 24, 24)
    )
    draw = ImageDraw.Draw(sheet)
    for c, (_key, title) in enumerate(columns):
        x = label_w + c * len(VIEWS) * TILE_W
        draw.text((x + 6, 4), title, fill=(230, 230, 230))
        for v, (_view, _azimuth, label) in enumerate(VIEWS):
            draw.text((x + v * TILE_W + 6, 19), label, fill=(170, 170, 170))
    luminance = np.array([0.2126, 0.7152, 0.0722])
    for r, e in enumerate(ELEVATIONS):
        tiles = [read_exr(tmp / f"{key}_{e:+05.1f}_{view}.exr") for key, view in tiles_per_row]
        # The row's exposure: Welkin's median sky luminance over both its views (above the
        # horizon row; the median leaves the sun's disc out) to 0.18.
        horizon_row = int(TILE_H * LAT_MAX / (LAT_MAX - LAT_MIN))
        welkin_sky = np.concatenate(
            [t[:horizon_row] for t, (key, _v) in zip(tiles, tiles_per_row) if key == "welkin"]
        )
        median = float(np.median(welkin_sky @ luminance))
        k = 0.18 / max(median, 1e-12)
        for c, tile in enumerate(tiles):
            x = np.clip(np.nan_to_num(tile * k), 0.0, None)
            x = x / (1.0 + x)
            srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
            sheet.paste(
                Image.fromarray((np.clip(srgb, 0, 1) * 255 + 0.5).astype(np.uint8)),
                (label_w + c * TILE_W, head_h + r * TILE_H),
            )
        y = head_h + r * TILE_H
        draw.text((6, y + 6), f"sun {e:+g} deg", fill=(230, 230, 230))
        draw.text((6, y + 22), f"EV {math.log2(1.0 / k):+.1f}", fill=(170, 170, 170))
        draw.line([(label_w, y), (sheet.width, y)], fill=(24, 24, 24))
    for c in range(1, len(columns)):  # a gap between the skies
        x = label_w + c * len(VIEWS) * TILE_W
        draw.line([(x, head_h), (x, sheet.height)], fill=(24, 24, 24), width=3)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out_png, optimize=True)
    print(
        f"time-of-day sheet: {out_png} ({out_png.stat().st_size // 1024} KB), columns: "
        + ", ".join(title for _key, title in columns)
    )


argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
parser = argparse.ArgumentParser()
parser.add_argument("--out", default=str(ROOT / "docs" / "time_of_day.png"))
parser.add_argument("--keep", default=None, help="keep the linear EXR tiles in this folder")
parser.add_argument("--blender5", default=None, help=argparse.SUPPRESS)
args, _unknown = parser.parse_known_args(argv)
if args.blender5:
    blender5_main(args.blender5)
else:
    main(pathlib.Path(args.out), args.keep)
