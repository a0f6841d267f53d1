# SPDX-License-Identifier: Apache-2.0
"""Aerial perspective end to end: `welkin aerial`, `welkin sky --scene`, and the module's
welkin.aerial_perspective and SceneDescription.

Depth files are written with welkin.write_exr (Debian has no OpenEXR binding for Python),
named as Blender names its passes ("Z", "Depth.Z", "<view layer>.Depth.Z"). Checks: the
passes' layers and channel names, that far pixels see lower transmittance and more
in-scattering than near ones, that sky pixels are T = 1 and no in-scattering, that the CLI
and the module give the same numbers (one core), and that bad input of every kind gets a
one-line error naming the option, a non-zero exit and no file.

Run with PYTHONPATH=build /usr/bin/python3 -m pytest tests/python/test_aerial.py.
"""

import json
import math
import os
import subprocess

import numpy as np
import pytest

import welkin
from cli_testing import CLI, assert_ctrl_c_cancels, files


PASS_CHANNELS = [f"Welkin.Aerial{p}.{c}" for p in ("Inscatter", "Transmittance") for c in "RGB"]

W, H = 96, 54


def write_channels(path, channels):
    """{channel name: (height, width) array} -> an EXR file (welkin.write_exr)."""
    names = list(channels)
    welkin.write_exr(
        str(path), np.stack([np.asarray(channels[n], np.float32) for n in names], axis=-1), names
    )


def read_channels(path):
    """An EXR file -> {channel name: (height, width) array} (welkin.read_exr)."""
    pixels, names = welkin.read_exr(str(path))
    return {n: pixels[..., i] for i, n in enumerate(names)}


def run(*args, cwd=None, timeout=120):
    return subprocess.run([CLI, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def assert_one_line_error(r, *needles):
    assert r.returncode != 0
    err = r.stderr.strip()
    assert err.startswith("welkin: error: "), err
    assert "\n" not in err, err
    for n in needles:
        assert n in err, f"{n!r} not in {err!r}"


def camera_along_x(height_m=200.0, pitch_deg=2.0, **fields):
    """Blender's matrix_world (rows) of a camera at (0, 0, height) looking along +X, tilted
    down by pitch: local -Z forward, +Y up, +X towards world -Y."""
    p = math.radians(pitch_deg)
    fwd = (math.cos(p), 0.0, -math.sin(p))
    up = (math.sin(p), 0.0, math.cos(p))
    right = (0.0, -1.0, 0.0)
    back = tuple(-v for v in fwd)
    cols = [right, up, back, (0.0, 0.0, height_m)]
    rows = [[cols[c][r] for c in range(4)] for r in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
    return {"matrix_world": rows, "type": "PERSP", "lens_mm": 35.0, "clip_end_m": 1e5, **fields}


def scene_dict(camera=None, width=W, height=H, percentage=100, **extra):
    s = {
        "version": 1,
        "atmosphere": "hazy",
        "sun": {"elevation_deg": 10, "azimuth_deg": 30},
        "resolution": {"x": width, "y": height, "percentage": percentage},
        **extra,
    }
    if camera is not False:
        s["camera"] = camera or camera_along_x()
    return s


def depth_image(height=H, width=W):
    """Rows top first: sky in the top third, then depth growing towards the horizon (far at
    the top of the ground, 40 km, near at the bottom, 50 m)."""
    z = np.full((height, width), np.inf, np.float32)
    ground = np.arange(height // 3, height)
    f = (ground - height // 3) / (height - 1 - height // 3)  # 0 at the horizon, 1 at the bottom
    z[ground, :] = (40e3 * np.exp(np.log(50.0 / 40e3) * f))[:, None]
    return z


@pytest.fixture
def frame(tmp_path):
    """A scene JSON and a multilayer depth EXR as Blender writes them."""
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(scene_dict()))
    z = depth_image()
    write_channels(
        tmp_path / "render.exr", {"ViewLayer.Combined.R": np.zeros_like(z), "ViewLayer.Depth.Z": z}
    )
    return tmp_path, scene, z


# --- good runs -----------------------------------------------------------------------------


def test_aerial_writes_both_passes_far_hazier_than_near(frame):
    d, scene, z = frame
    r = run("aerial", "--scene", scene, "--depth", "render.exr", "-o", "passes.exr", cwd=d)
    assert r.returncode == 0, r.stderr
    assert "passes.exr" in r.stdout
    passes = read_channels(d / "passes.exr")
    assert sorted(passes) == sorted(PASS_CHANNELS)
    L = np.stack([passes[f"Welkin.AerialInscatter.{c}"] for c in "RGB"], axis=-1)
    T = np.stack([passes[f"Welkin.AerialTransmittance.{c}"] for c in "RGB"], axis=-1)
    assert L.shape == (H, W, 3) and np.isfinite(L).all() and np.isfinite(T).all()
    assert (T >= 0).all() and (T <= 1).all() and (L >= 0).all()
    sky = ~np.isfinite(z)
    assert (T[sky] == 1).all() and (L[sky] == 0).all()  # the sky is left as rendered
    far, near = H // 3, H - 1  # 40 km and 50 m
    assert (T[far] < T[near]).all()
    assert (L[far] > L[near]).all()
    # Blue is scattered and extinguished most: the far haze transmits less blue than red.
    assert (T[far, :, 2] < T[far, :, 0]).all()
    # One core: the module gives the same numbers for the same scene and depth.
    Lm, Tm = welkin.aerial_perspective(scene.read_text(), z)
    np.testing.assert_array_equal(Lm, L)
    np.testing.assert_array_equal(Tm, T)
    # The file carries the scene that reproduces it.
    info = json.loads(run("exr-info", d / "passes.exr").stdout)
    assert info["width"] == W and info["height"] == H


@pytest.mark.parametrize("name", ["Z", "Depth.Z", "RenderLayer.Depth.Z"])
def test_depth_channel_is_found_as_blender_names_it(tmp_path, name):
    (tmp_path / "s.json").write_text(json.dumps(scene_dict()))
    z = depth_image()
    write_channels(tmp_path / "d.exr", {name: z, "R": np.zeros_like(z)})
    r = run("aerial", "--scene", "s.json", "--depth", "d.exr", "-o", "p.exr", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "p.exr" in files(tmp_path)


def test_depth_channel_option_picks_one_of_several_layers(tmp_path):
    (tmp_path / "s.json").write_text(json.dumps(scene_dict()))
    z = depth_image()
    write_channels(tmp_path / "d.exr", {"A.Depth.Z": z, "B.Depth.Z": z * 2})
    r = run("aerial", "--scene", "s.json", "--depth", "d.exr", "-o", "p.exr", cwd=tmp_path)
    assert_one_line_error(r, "--depth-channel", "A.Depth.Z", "B.Depth.Z")
    assert files(tmp_path) == ["d.exr", "s.json"]
    r = run(
        "aerial",
        "--scene",
        "s.json",
        "--depth",
        "d.exr",
        "--depth-channel",
        "B.Depth.Z",
        "-o",
        "p.exr",
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    Lm, _ = welkin.aerial_perspective((tmp_path / "s.json").read_text(), z * 2)
    np.testing.assert_array_equal(read_channels(tmp_path / "p.exr")["Welkin.AerialInscatter.G"], Lm[..., 1])


def test_methods_agree_and_orthographic_and_panoramic_cameras_run(tmp_path):
    z = depth_image()
    s = scene_dict()
    Lf, Tf = welkin.aerial_perspective(json.dumps(s), z, "froxel")
    Lr, Tr = welkin.aerial_perspective(json.dumps(s), z, "raymarch")
    ground = np.isfinite(z)
    big = Lr > 1e-3 * Lr.max()
    rel = np.abs(Lf - Lr)[big & ground[..., None]] / Lr[big & ground[..., None]]
    assert np.median(rel) < 0.01  # the tolerance of the C++ froxel-vs-march test
    assert np.abs(Tf - Tr).max() < 0.02
    for camera in (
        camera_along_x(type="ORTHO", ortho_scale=50.0),
        camera_along_x(type="PANO", panorama_type="EQUIRECTANGULAR"),
    ):
        camera.pop("lens_mm")
        for method in ("froxel", "raymarch"):
            L, T = welkin.aerial_perspective(json.dumps(scene_dict(camera)), z, method)
            assert np.isfinite(L).all() and (T[ground] < 1).all()


def test_percentage_scales_the_render(tmp_path):
    s = scene_dict(width=W * 2, height=H * 2, percentage=50)
    scene = welkin.SceneDescription.from_json_string(json.dumps(s))
    assert (scene.width, scene.height) == (W, H)
    L, T = welkin.aerial_perspective(scene, depth_image())
    assert L.shape == (H, W, 3)


def test_scene_round_trips_through_the_module(tmp_path):
    scene = welkin.SceneDescription.from_json_string(json.dumps(scene_dict()))
    text = scene.to_json_string()
    assert welkin.SceneDescription.from_json_string(text).to_json_string() == text
    scene.to_json(str(tmp_path / "a.json"))
    with pytest.raises(OSError):
        scene.to_json(str(tmp_path / "a.json"))
    j = json.loads(text)
    assert j["version"] == 1 and j["camera"]["type"] == "PERSP"
    assert j["atmosphere"]["name"] == welkin.Atmosphere.preset("hazy").name


def test_sky_from_a_scene_matches_the_same_options(tmp_path):
    s = scene_dict(origin_altitude_m=500.0, method="lut")
    (tmp_path / "s.json").write_text(json.dumps(s))
    r = run("sky", "--scene", "s.json", "--width", 32, "-o", "a.exr", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    r = run(
        "sky",
        "--preset",
        "hazy",
        "--sun-elevation",
        10,
        "--sun-azimuth",
        30,
        "--altitude",
        500,
        "--width",
        32,
        "--method",
        "lut",
        "-o",
        "b.exr",
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    a = read_channels(tmp_path / "a.exr")
    b = read_channels(tmp_path / "b.exr")
    for c in "RGB":
        np.testing.assert_allclose(a[c], b[c], rtol=1e-6)
    r = run("sky", "--scene", "s.json", "--preset", "clear", "-o", "c.exr", cwd=tmp_path)
    assert_one_line_error(r, "--preset", "--scene")


# --- bad input -----------------------------------------------------------------------------


def bad_case(tmp_path, case):
    """(args, needles) for one bad-input case, with its files written in tmp_path."""
    z = depth_image()
    good = scene_dict()
    (tmp_path / "good.json").write_text(json.dumps(good))
    write_channels(tmp_path / "good.exr", {"ViewLayer.Depth.Z": z})
    base = ["--scene", "good.json", "--depth", "good.exr"]
    if case == "no_camera":
        (tmp_path / "s.json").write_text(json.dumps(scene_dict(camera=False)))
        return ["--scene", "s.json", "--depth", "good.exr"], ["--scene", "camera", "no camera"]
    if case == "bad_camera":
        (tmp_path / "s.json").write_text(json.dumps(scene_dict(camera_along_x(lens_mm=-1))))
        return ["--scene", "s.json", "--depth", "good.exr"], ["--scene", "camera.lens_mm"]
    if case == "fisheye":
        cam = camera_along_x(type="PANO", panorama_type="FISHEYE_EQUISOLID")
        (tmp_path / "s.json").write_text(json.dumps(scene_dict(cam)))
        return ["--scene", "s.json", "--depth", "good.exr"], ["camera.panorama_type", "EQUIRECTANGULAR"]
    if case == "malformed_scene":
        (tmp_path / "s.json").write_text("{")
        return ["--scene", "s.json", "--depth", "good.exr"], ["--scene", "malformed"]
    if case == "missing_scene":
        return ["--scene", "nope.json", "--depth", "good.exr"], ["--scene", "nope.json"]
    if case == "missing_depth_file":
        return ["--scene", "good.json", "--depth", "nope.exr"], ["--depth", "nope.exr"]
    if case == "missing_depth_channel":
        write_channels(tmp_path / "d.exr", {"ViewLayer.Combined.R": z})
        return ["--scene", "good.json", "--depth", "d.exr"], [
            "--depth-channel",
            "Z pass",
            "ViewLayer.Combined.R",
        ]
    if case == "unknown_depth_channel":
        return base + ["--depth-channel", "Q"], ["--depth-channel", "'Q'"]
    if case in ("depth_nan", "depth_negative", "depth_minus_inf"):
        bad = z.copy()
        bad[40, 7] = {"depth_nan": np.nan, "depth_negative": -3.0, "depth_minus_inf": -np.inf}[case]
        write_channels(tmp_path / "d.exr", {"Z": bad})
        return ["--scene", "good.json", "--depth", "d.exr"], ["--depth", "x 7, y 40"]
    if case == "wrong_size":
        write_channels(tmp_path / "d.exr", {"Z": z[:, :-1]})
        return ["--scene", "good.json", "--depth", "d.exr"], ["--depth", f"{W - 1} x {H}", f"{W} x {H}"]
    if case == "huge_render":
        (tmp_path / "s.json").write_text(json.dumps(scene_dict(width=65536, height=65536, percentage=1000)))
        return ["--scene", "s.json", "--depth", "good.exr"], ["--scene", "resolution", "GiB"]
    if case == "bad_method":
        return base + ["--method", "fast"], ["--method"]
    raise AssertionError(case)


BAD_CASES = [
    "no_camera",
    "bad_camera",
    "fisheye",
    "malformed_scene",
    "missing_scene",
    "missing_depth_file",
    "missing_depth_channel",
    "unknown_depth_channel",
    "depth_nan",
    "depth_negative",
    "depth_minus_inf",
    "wrong_size",
    "huge_render",
    "bad_method",
]


@pytest.mark.parametrize("case", BAD_CASES)
def test_bad_input_is_refused_and_nothing_written(tmp_path, case):
    args, needles = bad_case(tmp_path, case)
    before = files(tmp_path)
    r = run("aerial", *args, "-o", "out.exr", cwd=tmp_path)
    assert_one_line_error(r, *needles)
    assert r.returncode == 2, r.stderr
    assert files(tmp_path) == before


@pytest.mark.parametrize(
    "target", ["/proc/welkin_aerial_test.exr", "no/such/dir/p.exr", "afile/p.exr", "adir"]
)
def test_unwritable_output_is_refused(tmp_path, target):
    args, _ = bad_case(tmp_path, "bad_method")
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir()
    before = files(tmp_path)
    r = run("aerial", *args[:4], "-o", target, cwd=tmp_path)
    assert_one_line_error(r, target)
    # A directory (like a device or FIFO) is bad input naming --output: exit code 2.
    assert r.returncode == (2 if target == "adir" else 1)
    assert files(tmp_path) == before
    assert not os.path.exists("/proc/welkin_aerial_test.exr")


def test_existing_output_is_kept_unless_overwrite(frame):
    d, scene, _ = frame
    (d / "passes.exr").write_bytes(b"precious")
    r = run("aerial", "--scene", scene, "--depth", "render.exr", "-o", "passes.exr", cwd=d)
    assert_one_line_error(r, "passes.exr", "--overwrite")
    assert (d / "passes.exr").read_bytes() == b"precious"
    r = run("aerial", "--scene", scene, "--depth", "render.exr", "-o", "passes.exr", "--overwrite", cwd=d)
    assert r.returncode == 0, r.stderr
    assert sorted(read_channels(d / "passes.exr")) == sorted(PASS_CHANNELS)
    assert files(d) == ["passes.exr", "render.exr", "scene.json"]


def test_module_bad_input_raises_value_error_naming_the_parameter():
    s = json.dumps(scene_dict())
    with pytest.raises(ValueError, match="camera"):
        welkin.aerial_perspective(json.dumps(scene_dict(camera=False)), depth_image())
    with pytest.raises(ValueError, match=r"depth.*shape \(54, 95\)"):
        welkin.aerial_perspective(s, depth_image()[:, :-1])
    bad = depth_image()
    bad[50, 3] = np.nan
    with pytest.raises(ValueError, match="depth.*x 3, y 50.*NaN"):
        welkin.aerial_perspective(s, bad)
    with pytest.raises(ValueError, match="method"):
        welkin.aerial_perspective(s, depth_image(), "fast")
    # More than this machine's memory: MemoryError naming the parameter (issue 18).
    with pytest.raises(MemoryError, match="resolution"):
        welkin.aerial_perspective(
            json.dumps(scene_dict(width=65536, height=65536, percentage=1000)), depth_image()
        )
    with pytest.raises(ValueError, match="camera.sensor_fit"):
        welkin.SceneDescription.from_json_string(json.dumps(scene_dict(camera_along_x(sensor_fit="auto"))))


def test_ctrl_c_cancels_cleanly(tmp_path):
    # The per-pixel march of a 1920 x 1080 frame runs for many seconds on two cores.
    s = scene_dict(width=1920, height=1080, aerial={"method": "raymarch", "raymarch_steps": 256})
    (tmp_path / "s.json").write_text(json.dumps(s))
    write_channels(tmp_path / "d.exr", {"Z": depth_image(1080, 1920)})
    assert_ctrl_c_cancels(["aerial", "--scene", "s.json", "--depth", "d.exr", "-o", "c.exr"], tmp_path)
