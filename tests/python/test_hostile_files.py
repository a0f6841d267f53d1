# SPDX-License-Identifier: Apache-2.0
"""Hostile files and unbounded settings through the Python module and the CLI: every VDB of
the fuzz corpus (the seeds, the fuzzer's findings and three byte-flipped copies of a ball
VDB that corrupted the host's heap) loaded by welkin.VdbClouds in a fresh interpreter that
must exit normally; an EXR input that is a FIFO or declares 100000 x 100000 pixels; running
out of memory while converting an array; the wind offset's range; the add-on's checks of a
cloud layer's numbers and of the number of layers; `--help` and `--version` to a full disk.

Run with PYTHONPATH=build /usr/bin/python3 -m pytest tests/python/test_hostile_files.py.
"""

import math
import os
import pathlib
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import welkin
from cli_testing import CLI
from welkin_addon import cloud_export

ROOT = pathlib.Path(__file__).resolve().parents[2]
VDB_CORPUS = ROOT / "tests" / "fuzz" / "corpus" / "vdb"
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "build")}


def run_python(code, *args, timeout=120):
    """`code` in a fresh /usr/bin/python3 with the module on its path (the host process a
    crash would take down: Blender loads the module in its own)."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code), *map(str, args)],
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


LOAD_VDB = """
    import gc, sys
    import welkin
    path = sys.argv[1]
    for attempt in range(3):
        try:
            clouds = welkin.VdbClouds(path, max_memory_bytes=64 << 20)
            print("grid", clouds.active_voxel_count)
        except (OSError, ValueError, MemoryError) as error:
            assert path in str(error), error
            print(type(error).__name__, error)
    # The interpreter's own heap in use after the refusals: what used to crash at exit.
    junk = [bytearray(n % 4000 + 16) for n in range(20000)]
    del junk
    gc.collect()
"""


@pytest.mark.parametrize("vdb", sorted(VDB_CORPUS.glob("*.vdb")), ids=lambda p: p.name)
def test_every_vdb_of_the_corpus_loads_or_is_refused_and_the_interpreter_exits_normally(vdb):
    run = run_python(LOAD_VDB, vdb)
    assert run.returncode == 0, f"rc {run.returncode}:\n{run.stdout}\n{run.stderr[-2000:]}"
    lines = run.stdout.splitlines()
    # The same outcome each time. How a reader process that the file corrupts ends (the
    # signal named in parentheses) is up to the corrupted heap, not to Welkin.
    outcomes = {re.sub(r"reader process \([^)]*\)", "reader process", line) for line in lines}
    assert len(lines) == 3 and len(outcomes) == 1, run.stdout


def test_a_file_of_an_older_layout_is_refused_before_openvdb_reads_it():
    # Version 0 and a file-level metadata string declaring 943 MB in a 159-byte file: OpenVDB's
    # File::open would allocate it in this process (the fuzzer's out-of-memory finding).
    path = VDB_CORPUS / "version_zero_huge_metadata_string.vdb"
    assert path.stat().st_size < 200
    run = run_python(LOAD_VDB, path)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.count("file format version 0 is older than 222") == 3, run.stdout


def test_the_corpus_holds_the_ball_and_its_three_crashing_copies():
    names = {p.name for p in VDB_CORPUS.glob("*.vdb")}
    assert {"ball.vdb", "crash_ball_15.vdb", "crash_ball_36.vdb", "crash_ball_97.vdb"} <= names
    assert run_python(LOAD_VDB, VDB_CORPUS / "ball.vdb").stdout.startswith("grid ")
    for name in ("crash_ball_15.vdb", "crash_ball_36.vdb", "crash_ball_97.vdb"):
        assert "OSError" in run_python(LOAD_VDB, VDB_CORPUS / name).stdout


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "f.exr"
    os.mkfifo(path)
    return path


def test_read_exr_refuses_a_fifo_at_once(fifo):
    run = run_python(
        """
        import sys, welkin
        try:
            welkin.read_exr(sys.argv[1])
        except OSError as error:
            print(error)
    """,
        fifo,
        timeout=60,
    )
    assert run.returncode == 0 and "FIFO" in run.stdout and str(fifo) in run.stdout, run


@pytest.mark.parametrize(
    "args", [["exr-info", "{fifo}"], ["aerial", "--scene", "{scene}", "--depth", "{fifo}", "-o", "{out}"]]
)
def test_the_cli_refuses_a_fifo_at_once(fifo, tmp_path, args):
    scene = tmp_path / "scene.json"
    scene.write_text(
        '{"version": 1, "camera": {"matrix_world": [[1,0,0,0],[0,1,0,0],'
        '[0,0,1,2],[0,0,0,1]]}, "resolution": {"x": 8, "y": 4}}'
    )
    argv = [a.format(fifo=fifo, scene=scene, out=tmp_path / "out.exr") for a in args]
    run = subprocess.run([CLI, *argv], capture_output=True, text=True, timeout=60)
    assert run.returncode != 0 and "FIFO" in run.stderr, run
    assert not (tmp_path / "out.exr").exists()


EXR_CORPUS = ROOT / "tests" / "fuzz" / "corpus" / "exr"


@pytest.mark.parametrize("exr", sorted(EXR_CORPUS.glob("*.exr")), ids=lambda p: p.name)
def test_every_exr_of_the_corpus_reads_or_is_refused_at_once(exr):
    """An image, or OSError / MemoryError naming the file, within seconds and within a
    768 MiB address space (attribute_size_huge.exr: a string attribute that declared 721 MB in
    a 364-byte file, which OpenEXR allocated and cleared before reading it)."""
    run = run_python(
        """
        import resource, sys, time
        import welkin
        resource.setrlimit(resource.RLIMIT_AS, (768 << 20, resource.RLIM_INFINITY))
        t0 = time.monotonic()
        try:
            pixels, names = welkin.read_exr(sys.argv[1])
            print("image", pixels.shape, names)
        except (OSError, MemoryError) as error:
            assert sys.argv[1] in str(error), error
            print(type(error).__name__, error)
        print(f"{time.monotonic() - t0:.3f}")
    """,
        exr,
        timeout=60,
    )
    assert run.returncode == 0, f"rc {run.returncode}:\n{run.stdout}\n{run.stderr[-2000:]}"
    assert float(run.stdout.splitlines()[-1]) < 2.0, run.stdout
    assert "bad_alloc" not in run.stdout, run.stdout  # a bare std::bad_alloc names nothing
    if exr.name == "attribute_size_huge.exr":
        assert "header attribute 'Camera' declares 721420294 bytes" in run.stdout, run.stdout


def huge_exr(tmp_path):
    """A 4 x 3 RGB file whose header claims 100000 x 100000 pixels, with room for the chunk
    offset table of such an image (6250 entries of 8 bytes), so that OpenEXR opens it."""
    small = tmp_path / "small.exr"
    welkin.write_exr(str(small), np.full((3, 4, 3), 0.5, np.float32))
    data = bytearray(small.read_bytes())
    at = data.index(b"dataWindow\0box2i\0") + len(b"dataWindow\0box2i\0") + 4
    data[at : at + 16] = np.array([0, 0, 99999, 99999], "<i4").tobytes()
    path = tmp_path / "huge.exr"
    path.write_bytes(bytes(data) + bytes(64 << 10))
    return path


def test_read_exr_of_an_absurd_header_is_a_memory_error_naming_the_file(tmp_path):
    path = huge_exr(tmp_path)
    with pytest.raises(MemoryError, match="100000 x 100000") as error:
        welkin.read_exr(str(path))
    assert str(path) in str(error.value)


def test_running_out_of_memory_converting_an_array_is_a_memory_error():
    """float32 (6e7, 3) directions need a 1.4 GB float64 copy: under a 2.5 GB address-space
    limit numpy cannot make it, and that is MemoryError, not "not an array of numbers"."""
    run = run_python(
        """
        import resource
        import numpy as np
        import welkin
        atm = welkin.Atmosphere.preset("bruneton2017")
        dirs = np.zeros((60_000_000, 3), np.float32)
        dirs[:, 2] = 1.0
        resource.setrlimit(resource.RLIMIT_AS, (2_500_000_000, resource.RLIM_INFINITY))
        try:
            welkin.sky_radiance(atm, 0.0, (0.0, 0.0, 1.0), dirs, method="analytic", output="rgb")
            print("computed")
        except MemoryError as error:
            print("MemoryError", error)
        except ValueError as error:
            print("ValueError", error)
    """,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.startswith("MemoryError"), run.stdout


@pytest.mark.parametrize("wind", [(1e20, 0.0), (0.0, -1e300), (math.inf, 0.0), (1.5e9, 0.0)])
def test_the_wind_offset_has_a_range(wind):
    with pytest.raises(ValueError, match=r"wind_offset_m\[[01]\]: must be in \[-1000000000, 1000000000\] m"):
        welkin.CloudLayer(cloud_type="cumulus", wind_offset_m=wind)
    welkin.CloudLayer(cloud_type="cumulus", wind_offset_m=(1e9, -1e9))  # the bounds themselves


@pytest.mark.parametrize("field", ["wind_offset_m[0]", "wind_offset_m[1]", "evolution_m", "coverage"])
def test_a_layer_number_that_is_not_finite_is_named(field):
    """The add-on's layer (Blender allows NaN in a float property): named, not the JSON
    parser's "invalid literal" at some byte."""
    values = {k: 1.0 for k in cloud_export.LAYER_FIELDS}
    values["cloud_type"] = "cumulus"
    wind = [0.0, 0.0]
    if field.startswith("wind"):
        wind[int(field[-2])] = math.nan
    else:
        values[field] = math.nan
    with pytest.raises(ValueError, match=rf"^{re.escape(field)}: must be a finite number, got nan"):
        cloud_export.layer_dict(values, 1, wind)


def test_the_add_ons_layer_limit_is_the_cores():
    layer = '{"cloud_type": "cirrus"}'

    def scene(n):
        return f'{{"version": 1, "clouds": {{"layers": [{", ".join([layer] * n)}]}}}}'

    welkin.SceneDescription.from_json_string(scene(cloud_export.MAX_LAYERS))
    with pytest.raises(ValueError, match=f"at most {cloud_export.MAX_LAYERS}"):
        welkin.SceneDescription.from_json_string(scene(cloud_export.MAX_LAYERS + 1))


@pytest.mark.parametrize("args", [["--version"], ["sky", "--help"], ["--help"]])
def test_help_and_version_to_a_full_disk_fail(args):
    """As coreutils do (`ls --help > /dev/full`: exit 1 and a line on stderr)."""
    with open("/dev/full", "w") as full:
        run = subprocess.run([CLI, *args], stdout=full, stderr=subprocess.PIPE, text=True, timeout=60)
    assert run.returncode != 0 and "No space left on device" in run.stderr, run
    ok = subprocess.run([CLI, *args], capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0 and ok.stdout and not ok.stderr
