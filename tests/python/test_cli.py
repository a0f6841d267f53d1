# SPDX-License-Identifier: Apache-2.0
"""End-to-end tests of the `welkin` command-line tool.

Runs the built binary: $WELKIN_CLI, or build/welkin from the repository root. Checks that
bad input of every kind gets a one-line error naming the option (and its range), a
non-zero exit and no file; that a good render writes a complete EXR whose content is
right (size, channels, no NaN, and the sun disc carrying exactly the direct irradiance
`welkin sun` reports); and that Ctrl-C cancels cleanly. EXR files are inspected with
`welkin exr-info` (Debian has no OpenEXR binding for Python).

Run with /usr/bin/python3 -m pytest tests/python/test_cli.py.
"""

import json
import os
import subprocess
import time

import numpy as np
import pytest

from cli_testing import CLI, assert_ctrl_c_cancels, children_cpu_seconds, files


pytestmark = pytest.mark.skipif(not os.access(CLI, os.X_OK), reason=f"no CLI binary at {CLI}")


def welkin(*args, cwd=None, timeout=120):
    return subprocess.run([CLI, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def exr_info(path, integral=False):
    r = welkin("exr-info", path, *(["--integral"] if integral else []))
    assert r.returncode == 0, r.stderr
    info = json.loads(r.stdout)
    info["by_name"] = {c["name"]: c for c in info["channels"]}
    return info


def assert_one_line_error(r, *needles):
    assert r.returncode != 0
    err = r.stderr.strip()
    assert err.startswith("welkin: error: "), err
    assert "\n" not in err, err
    for n in needles:
        assert n in err, f"{n!r} not in {err!r}"


# --- help, presets, atmosphere, sun --------------------------------------------------------


def test_help_explains_every_option_with_units():
    r = welkin("--help")
    assert r.returncode == 0
    for sub in ("sky", "sun", "presets", "atmosphere", "exr-info"):
        assert sub in r.stdout
    r = welkin("sky", "--help")
    assert r.returncode == 0
    text = " ".join(r.stdout.split())
    for option in (
        "--preset",
        "--atmosphere",
        "--sun-elevation",
        "--sun-azimuth",
        "--altitude",
        "--width",
        "--method",
        "--exposure",
        "--spectral",
        "--half",
        "--float",
        "--no-sun-disc",
        "--overwrite",
        "--output",
        "--threads",
    ):
        assert option in text, option
    for unit in ("degrees", "metres", "pixels", "W m^-2 sr^-1", "counter-clockwise from +X"):
        assert unit in text, unit
    assert welkin("--version").stdout.startswith("welkin ")


def test_presets_lists_the_builtin_atmospheres():
    r = welkin("presets", "--json")
    assert r.returncode == 0
    names = json.loads(r.stdout)
    assert {
        "clear_day",
        "bruneton2017",
        "clear",
        "hazy",
        "polluted",
        "desert_dust",
        "maritime",
        "mars",
    } <= set(names)
    text = welkin("presets").stdout
    assert all(n in text for n in names)


def test_atmosphere_writes_json_that_round_trips(tmp_path):
    out = tmp_path / "atm.json"
    r = welkin("atmosphere", "--preset", "clear", "-o", out)
    assert r.returncode == 0, r.stderr
    assert str(out) in r.stdout
    atm = json.loads(out.read_text())
    assert atm["wavelengths_nm"] == [620.0, 560.0, 480.0, 440.0]  # the default four
    # Refuses to overwrite, then does with --overwrite.
    before = out.read_text()
    r = welkin("atmosphere", "--preset", "bruneton2017", "-o", out)
    assert_one_line_error(r, str(out), "--overwrite")
    assert out.read_text() == before
    r = welkin("atmosphere", "--preset", "bruneton2017", "-o", out, "--overwrite")
    assert r.returncode == 0
    # The file drives `welkin sun` exactly like the preset.
    a = json.loads(welkin("sun", "--atmosphere", out, "--sun-elevation", 25).stdout)
    b = json.loads(welkin("sun", "--preset", "bruneton2017", "--sun-elevation", 25).stdout)
    assert a["direct_irradiance_W_m2_nm"] == pytest.approx(b["direct_irradiance_W_m2_nm"], rel=1e-12)
    # Without -o: standard output.
    assert json.loads(welkin("atmosphere", "--preset", "mars").stdout)["bottom_radius_m"] > 1e6


def test_sun_reports_transmittance_and_direct_irradiance():
    s = json.loads(welkin("sun", "--sun-elevation", 30, "--sun-azimuth", 90).stdout)
    assert s["visible_fraction"] == 1.0
    assert s["sun_direction"] == pytest.approx([0.0, 0.8660254, 0.5], abs=1e-7)
    for e, t, d in zip(s["solar_irradiance_W_m2_nm"], s["transmittance"], s["direct_irradiance_W_m2_nm"]):
        assert 0.0 < t < 1.0
        assert d == pytest.approx(e * t, rel=1e-12)
    # Blue is dimmed most (Rayleigh), so the 440 nm transmittance is the lowest.
    assert s["transmittance"][2] < s["transmittance"][1] < s["transmittance"][0]
    assert all(v > 0 for v in s["direct_irradiance_rgb_W_m2"])
    # Sun on the horizon: half the disc; below: nothing, and no NaN anywhere.
    assert json.loads(welkin("sun", "--sun-elevation", 0).stdout)["visible_fraction"] == pytest.approx(0.5)
    night = json.loads(welkin("sun", "--sun-elevation", -10).stdout)
    assert night["direct_irradiance_W_m2_nm"] == [0.0] * len(night["solar_irradiance_W_m2_nm"])
    assert night["direct_irradiance_rgb_W_m2"] == [0.0, 0.0, 0.0]
    spectral = json.loads(welkin("sun", "--spectral").stdout)
    assert len(spectral["wavelengths_nm"]) == 48


# --- bad input -------------------------------------------------------------------------------


def _write(path, text):
    path.write_text(text)
    return path


BAD_JSON = {
    "negative_radius": (
        '{"preset": "bruneton2017", "bottom_radius_m": -5}',
        ["--atmosphere", "bottom_radius_m", "[1000, 1000000000]", "-5"],
    ),
    "inverted_radii": (
        '{"preset": "bruneton2017", "bottom_radius_m": 6420000, "top_radius_m": 6360000}',
        ["--atmosphere", "top_radius_m", "greater than bottom_radius_m"],
    ),
    "malformed": ('{"preset": "bruneton2017",', ["--atmosphere", "malformed"]),
    "unknown_key": ('{"preset": "bruneton2017", "rayleih": {}}', ["--atmosphere", "rayleih"]),
}


@pytest.mark.parametrize("case", sorted(BAD_JSON))
@pytest.mark.parametrize("command", ["sky", "sun"])
def test_bad_atmosphere_json_is_refused(tmp_path, case, command):
    text, needles = BAD_JSON[case]
    f = _write(tmp_path / "atm.json", text)
    before = files(tmp_path)
    r = welkin(command, "--atmosphere", f, cwd=tmp_path)
    assert_one_line_error(r, *needles, "atm.json")
    assert r.returncode == 2
    assert files(tmp_path) == before  # nothing written


BAD_ARGS = {
    "unknown_preset": (["--preset", "nope"], ["--preset", "nope", "bruneton2017"]),
    "missing_json": (["--atmosphere", "missing.json"], ["--atmosphere", "missing.json"]),
    "width_small": (["--width", 3], ["--width", "4", "16384"]),
    "width_odd": (["--width", 7], ["--width", "even"]),
    "elevation": (["--sun-elevation", 100], ["--sun-elevation", "-90", "90"]),
    "elevation_nan": (["--sun-elevation", "nan"], ["--sun-elevation", "[-90, 90]"]),
    "azimuth": (["--sun-azimuth", 1000], ["--sun-azimuth", "360"]),
    "altitude": (["--altitude", -1], ["--altitude", "0"]),
    "exposure": (["--exposure", 0], ["--exposure", "(0, 1e6]"]),
    "method": (["--method", "magic"], ["--method", "magic"]),
    "half_and_float": (["--half", "--float"], ["--half", "--float"]),
    "spectral_with_json": (["--spectral", "--atmosphere", "ATM"], ["--spectral"]),
    "threads": (["--threads", 0], ["--threads"]),
    "unknown_option": (["--frobnicate"], ["--frobnicate"]),
}


@pytest.mark.parametrize("case", sorted(BAD_ARGS))
def test_bad_sky_arguments_are_refused(tmp_path, case):
    args, needles = BAD_ARGS[case]
    atm = tmp_path / "ok.json"
    atm.write_text(welkin("atmosphere", "--preset", "bruneton2017").stdout)
    args = [str(atm) if a == "ATM" else a for a in args]
    before = files(tmp_path)
    width = [] if "--width" in args else ["--width", 16]
    r = welkin("sky", *width, *args, "-o", "out.exr", cwd=tmp_path)
    assert_one_line_error(r, *needles)
    assert r.returncode == 2
    assert files(tmp_path) == before


@pytest.mark.parametrize(
    "target", ["/proc/welkin_cli_test.exr", "no/such/dir/sky.exr", "afile/sky.exr", "adir"]
)
def test_unwritable_output_is_refused_before_rendering(tmp_path, target):
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir()
    before = files(tmp_path)
    t0 = time.monotonic()
    # raymarch at 1024 takes many seconds: the refusal must come before any rendering.
    r = welkin("sky", "--method", "raymarch", "--width", 1024, "-o", target, cwd=tmp_path)
    assert time.monotonic() - t0 < 5.0
    assert_one_line_error(r, target)
    # A directory (like a device or FIFO) is refused as bad input, naming --output.
    assert r.returncode == (2 if target == "adir" else 1)
    assert files(tmp_path) == before
    assert not os.path.exists("/proc/welkin_cli_test.exr")


def test_existing_output_is_never_overwritten_without_overwrite(tmp_path):
    out = tmp_path / "sky.exr"
    out.write_bytes(b"precious")
    r = welkin("sky", "--width", 16, "-o", out)
    assert_one_line_error(r, str(out), "--overwrite")
    assert out.read_bytes() == b"precious"
    assert files(tmp_path) == ["sky.exr"]


# --- good renders (need a working lut method) ----------------------------------------------


def test_good_render_writes_a_complete_hdri(tmp_path):
    r = welkin(
        "sky",
        "--method",
        "lut",
        "--width",
        256,
        "--sun-elevation",
        25,
        "--sun-azimuth",
        60,
        "-o",
        "sky.exr",
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    out = tmp_path / "sky.exr"
    assert f"wrote {out}" in r.stdout
    assert files(tmp_path) == ["sky.exr"]  # no temporary file left
    info = exr_info(out)
    assert (info["width"], info["height"]) == (256, 128)
    assert sorted(info["by_name"]) == ["B", "G", "R"]
    for c in info["channels"]:
        assert c["non_finite"] == 0
        assert c["min"] >= 0.0
        assert c["max"] > 1e5  # the sun's disc (~3e6 W m^-2 sr^-1 in R)
    # Daylight sky without the (reddish-white, very bright) disc: blue on average.
    r = welkin(
        "sky",
        "--method",
        "lut",
        "--width",
        256,
        "--sun-elevation",
        25,
        "--no-sun-disc",
        "-o",
        "nodisc.exr",
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    sky = exr_info(tmp_path / "nodisc.exr")["by_name"]
    assert sky["B"]["mean"] > sky["G"]["mean"] > sky["R"]["mean"] > 0.0
    assert sky["R"]["max"] < 1e3  # no disc


@pytest.mark.parametrize("width", [64, 512])
def test_sun_disc_carries_exactly_the_direct_irradiance(tmp_path, width):
    """HDRI with the disc minus HDRI without = `welkin sun`'s direct RGB irradiance."""
    common = ["--method", "lut", "--width", width, "--sun-elevation", 12, "--sun-azimuth", -30]
    assert welkin("sky", *common, "-o", "a.exr", cwd=tmp_path).returncode == 0
    assert welkin("sky", *common, "--no-sun-disc", "-o", "b.exr", cwd=tmp_path).returncode == 0
    a = exr_info(tmp_path / "a.exr", integral=True)["by_name"]
    b = exr_info(tmp_path / "b.exr", integral=True)["by_name"]
    sun = json.loads(welkin("sun", "--sun-elevation", 12, "--sun-azimuth", -30).stdout)
    for k, name in enumerate("RGB"):
        disc = a[name]["solid_angle_integral"] - b[name]["solid_angle_integral"]
        assert disc == pytest.approx(sun["direct_irradiance_rgb_W_m2"][k], rel=1e-4)


def test_render_variants(tmp_path):
    # Exposure multiplies everything.
    base = ["--method", "lut", "--width", 64, "--sun-elevation", 40]
    assert welkin("sky", *base, "-o", "e1.exr", cwd=tmp_path).returncode == 0
    assert welkin("sky", *base, "--exposure", 0.5, "-o", "e2.exr", cwd=tmp_path).returncode == 0
    e1, e2 = exr_info(tmp_path / "e1.exr"), exr_info(tmp_path / "e2.exr")
    for name in "RGB":
        assert e2["by_name"][name]["mean"] == pytest.approx(0.5 * e1["by_name"][name]["mean"], rel=1e-5)
    # Multilayer names, half floats (the disc is clamped, with a warning), spectral.
    # (512 wide: the disc's pixels, ~3e6 W m^-2 sr^-1, exceed the half range.)
    r = welkin(
        "sky", "--method", "lut", "--width", 512, "--multilayer", "--half", "-o", "m.exr", cwd=tmp_path
    )
    assert r.returncode == 0, r.stderr
    assert "clamped" in r.stderr
    m = exr_info(tmp_path / "m.exr")
    assert sorted(m["by_name"]) == ["Welkin.Sky.B", "Welkin.Sky.G", "Welkin.Sky.R"]
    assert m["by_name"]["Welkin.Sky.R"]["max"] == 65504.0
    r = welkin("sky", *base, "--spectral", "--spectral-channels", "-o", "s.exr", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    s = exr_info(tmp_path / "s.exr")
    assert len(s["channels"]) == 48
    assert "S0.550nm" in s["by_name"]
    assert all(c["non_finite"] == 0 for c in s["channels"])
    # --overwrite replaces.
    r = welkin("sky", *base, "--exposure", 2, "--overwrite", "-o", "e1.exr", cwd=tmp_path)
    assert r.returncode == 0
    assert exr_info(tmp_path / "e1.exr")["by_name"]["G"]["mean"] == pytest.approx(
        2 * e1["by_name"]["G"]["mean"], rel=1e-5
    )
    # Extreme but valid: sun below the horizon, observer in space; no NaN.
    for extra in (["--sun-elevation", -30], ["--altitude", 1e7, "--sun-elevation", -80]):
        r = welkin(
            "sky", "--method", "lut", "--width", 64, *extra, "--overwrite", "-o", "x.exr", cwd=tmp_path
        )
        assert r.returncode == 0, r.stderr
        assert all(c["non_finite"] == 0 for c in exr_info(tmp_path / "x.exr")["channels"])


# --- Ctrl-C ----------------------------------------------------------------------------------


def test_ctrl_c_cancels_cleanly_and_writes_nothing(tmp_path):
    # raymarch at 1024 x 512 runs for many seconds on two cores; interrupt it midway.
    assert_ctrl_c_cancels(["sky", "--method", "raymarch", "--width", "1024", "-o", "c.exr"], tmp_path)


# --- hostile input and careful output (issue 18, items 4-8) ---------------------------------


def test_overwrite_writes_through_a_symlink_and_keeps_it(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "real" / "sky.exr").write_bytes(b"old")
    (tmp_path / "real" / "atm.json").write_text("old")
    os.symlink("real/sky.exr", tmp_path / "sky.exr")
    os.symlink("real/atm.json", tmp_path / "atm.json")
    r = welkin("sky", "--width", 16, "-o", "sky.exr", "--overwrite", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    r = welkin("atmosphere", "--preset", "clear", "-o", "atm.json", "--overwrite", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert os.path.islink(tmp_path / "sky.exr") and os.path.islink(tmp_path / "atm.json")
    assert exr_info(tmp_path / "real" / "sky.exr")["width"] == 16
    assert json.loads((tmp_path / "real" / "atm.json").read_text())["name"]
    assert files(tmp_path / "real") == ["atm.json", "sky.exr"]


@pytest.mark.parametrize("kind", ["fifo", "dir", "device", "link_to_fifo"])
@pytest.mark.parametrize("command", [["sky", "--width", 16], ["atmosphere", "--preset", "clear"]])
def test_overwrite_refuses_a_device_fifo_or_directory(tmp_path, kind, command):
    if kind in ("fifo", "link_to_fifo"):
        os.mkfifo(tmp_path / "fifo")
        target = str(tmp_path / "fifo")
        if kind == "link_to_fifo":
            os.symlink(target, tmp_path / "link")
            target = str(tmp_path / "link")
    elif kind == "dir":
        (tmp_path / "adir").mkdir()
        target = str(tmp_path / "adir")
    else:
        target = "/dev/null"
    before = files(tmp_path)
    r = welkin(*command, "-o", target, "--overwrite", cwd=tmp_path, timeout=30)
    assert_one_line_error(r, "--output", target)
    assert r.returncode == 2
    assert files(tmp_path) == before
    assert not os.path.isfile("/dev/null")  # still the device


@pytest.mark.parametrize("command", [["sky", "--width", 16], ["sun"]])
def test_atmosphere_from_a_device_fifo_or_directory_is_refused_at_once(tmp_path, command):
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "adir").mkdir()
    for source, needle in [
        ("/dev/zero", "character device"),
        (tmp_path / "fifo", "FIFO"),
        (tmp_path / "adir", "is a directory"),
    ]:
        t0 = time.monotonic()
        r = welkin(*command, "--atmosphere", source, cwd=tmp_path, timeout=30)
        assert time.monotonic() - t0 < 5.0
        assert_one_line_error(r, "--atmosphere", str(source), needle)
        assert r.returncode == 2


def test_json_number_overflow_names_the_file_and_the_key(tmp_path):
    (tmp_path / "atm.json").write_text('{"preset": "clear", "mie": {"g": 1e999}}')
    r = welkin("sun", "--atmosphere", tmp_path / "atm.json")
    assert_one_line_error(r, "--atmosphere", "mie.g", "number out of range", str(tmp_path / "atm.json"))
    assert r.returncode == 2
    (tmp_path / "scene.json").write_text('{"version": 1, "sun": {"direction": [0, 0, -1e400]}}')
    r = welkin("sky", "--width", 16, "--scene", tmp_path / "scene.json", "-o", tmp_path / "x.exr")
    assert_one_line_error(r, "sun.direction[2]", "number out of range")
    assert r.returncode == 2


def test_too_many_density_or_cloud_layers_are_refused_at_validation(tmp_path):
    layer = {"width_m": 1000, "constant": 1}
    (tmp_path / "atm.json").write_text(
        json.dumps({"preset": "clear", "rayleigh": {"density": {"layers": [layer] * 100000}}})
    )
    cpu0 = children_cpu_seconds()
    r = welkin("sun", "--atmosphere", tmp_path / "atm.json")
    assert_one_line_error(r, "rayleigh.density.layers", "32")
    assert r.returncode == 2
    (tmp_path / "scene.json").write_text(json.dumps({"version": 1, "clouds": {"layers": [{}] * 1000}}))
    r = welkin("sky", "--width", 16, "--scene", tmp_path / "scene.json", "-o", tmp_path / "x.exr")
    assert_one_line_error(r, "clouds.layers", "32")
    assert r.returncode == 2
    assert children_cpu_seconds() - cpu0 < 10.0  # refused while reading, not after minutes of work


@pytest.mark.parametrize("seed", ["-1", "1e23", "18446744073709551616", "1.5", "x"])
def test_seed_out_of_range_is_refused_with_the_range(tmp_path, seed):
    r = welkin("sky", "--width", 16, "--seed", seed, "-o", "x.exr", cwd=tmp_path)
    assert_one_line_error(r, "--seed", "18446744073709551615", seed)
    assert r.returncode == 2
    assert files(tmp_path) == []


def test_largest_seed_is_accepted(tmp_path):
    r = welkin("sky", "--width", 16, "--seed", "18446744073709551615", "-o", "x.exr", cwd=tmp_path)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("command", [["atmosphere", "--preset", "clear"], ["sun"], ["presets"]])
def test_a_full_standard_output_is_an_error(command):
    with open("/dev/full", "w") as full:
        r = subprocess.run([CLI, *command], stdout=full, stderr=subprocess.PIPE, text=True, timeout=60)
    assert r.returncode != 0
    assert "standard output" in r.stderr and "No space left" in r.stderr


def test_concurrent_json_writers_to_one_path_all_succeed(tmp_path):
    procs = [
        subprocess.Popen(
            [CLI, "atmosphere", "--preset", "clear", "-o", "atm.json", "--overwrite"],
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for _ in range(8)
    ]
    for p in procs:
        _, err = p.communicate(timeout=60)
        assert p.returncode == 0, err
    assert files(tmp_path) == ["atm.json"]
    json.loads((tmp_path / "atm.json").read_text())


def _interrupt_during_write(tmp_path, signals):
    """Starts a big EXR write, waits for its temporary file, then sends SIGINT `signals`
    times. Returns the process's exit status; skips if no write was caught."""
    import signal

    p = subprocess.Popen(
        [CLI, "sky", "--method", "lut", "--width", "8192", "--threads", "1", "-o", "big.exr"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and p.poll() is None:
        if any(".welkin-" in f for f in files(tmp_path)):
            break
        time.sleep(0.02)
    else:
        p.kill()
        p.communicate()
        pytest.skip("the write was not caught in progress")
    for _ in range(signals):  # back to back: the second arrives while the first unwinds
        p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    return p.returncode, err


def test_ctrl_c_during_the_exr_write_cancels_it_and_removes_the_temporary(tmp_path):
    rc, err = _interrupt_during_write(tmp_path, 1)
    assert rc == 130, err
    assert "cancelled" in err
    assert files(tmp_path) == []


def test_second_ctrl_c_during_the_exr_write_leaves_no_temporary(tmp_path):
    rc, err = _interrupt_during_write(tmp_path, 2)
    assert rc in (130, -2), err  # cancelled after the first, or ended by the second
    assert files(tmp_path) == []


def test_presets_print_their_aerosol_optical_depth_and_the_option_sets_it(tmp_path):
    lines = welkin("presets").stdout.splitlines()
    assert lines[0].startswith("clear_day") and "(default)" in lines[0]
    for line in lines:
        if not line.startswith(("mars", "bruneton2017")):
            tau = float(line.split("aerosol optical depth at 550 nm ")[1].split(",")[0])
            assert 0.05 <= tau <= 0.7, line
    base = json.loads(welkin("atmosphere", "--preset", "hazy").stdout)
    thin = json.loads(welkin("atmosphere", "--preset", "hazy", "--aerosol-optical-depth", "0.0327").stdout)
    # The default channels bracket 550 nm by 480 and 560 nm, across the kink of OPAC's two
    # Angstrom exponents at 500 nm: the interpolated column is within 0.2 % of 0.327.
    np.testing.assert_allclose(
        np.asarray(thin["mie"]["extinction"]), 0.1 * np.asarray(base["mie"]["extinction"]), rtol=3e-3
    )
    t = json.loads(welkin("atmosphere", "--turbidity", "2").stdout)
    d = json.loads(welkin("atmosphere").stdout)
    ratio = np.asarray(t["mie"]["extinction"]) / np.asarray(d["mie"]["extinction"])
    np.testing.assert_allclose(ratio, 0.1007 / 0.12, rtol=2e-3)
    r = welkin("sky", "--aerosol-optical-depth", "11", "-o", "x.exr", cwd=tmp_path)
    assert r.returncode == 2 and "--aerosol-optical-depth" in r.stderr
    assert not (tmp_path / "x.exr").exists()
