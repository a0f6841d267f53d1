# SPDX-License-Identifier: Apache-2.0
"""Bake for Farm's Blender-free part (addon/welkin/farm_bake.py): the frame key changes
with each of its inputs and only with them, the sequence's file names are the ones
Blender reads for frame F (digits at the end: F - start + 1), the image user maps the
range onto files 1..N, varying values and stale frames are found, and a record of another
format version is not read. Blender's own reading of the files is
tests/blender/test_farm_bake.py."""

import pytest

from welkin_addon import farm_bake


def test_frame_key_depends_on_every_input_only():
    base = farm_bake.frame_key("sky", '{"camera": 1}', "CYCLES")
    assert base == farm_bake.frame_key("sky", '{"camera": 1}', "CYCLES")
    assert len(base) == 64 and int(base, 16) >= 0
    others = {
        farm_bake.frame_key("sky2", '{"camera": 1}', "CYCLES"),
        farm_bake.frame_key("sky", '{"camera": 2}', "CYCLES"),
        farm_bake.frame_key("sky", '{"camera": 1}', "BLENDER_EEVEE"),
        # The parts are length-prefixed: moving text from one to the next changes the key.
        farm_bake.frame_key("sky{", '"camera": 1}', "CYCLES"),
    }
    assert base not in others and len(others) == 4


def test_sequence_path_and_image_user():
    assert farm_bake.sequence_path("Shot 1", "Welkin Sky", 1) == "//welkin_farm/Shot_1/Welkin_Sky_0001.exr"
    assert farm_bake.sequence_path("a/b", "x.y", 12) == "//welkin_farm/a_b/x_y_0012.exr"
    with pytest.raises(ValueError, match="index must be at least 1"):
        farm_bake.sequence_path("s", "r", 0)
    user = farm_bake.image_user(-2, 5)
    assert user == {"frame_start": -2, "frame_duration": 8, "frame_offset": 0}
    # Blender's rule: number = frame - start + 1 (clamped to 1..duration) + offset.
    files = [f - user["frame_start"] + 1 + user["frame_offset"] for f in farm_bake.frames_of(-2, 5)]
    assert files == list(range(1, 9))
    with pytest.raises(ValueError, match="frame_end"):
        farm_bake.frames_of(5, 4)


def test_varying_stale_and_ranges():
    frames = [{"a": 1.0, "b": (0.0, 1.0)}, {"a": 1.0, "b": (0.0, 2.0)}, {"a": 1.0, "b": (0.0, 1.0)}]
    assert farm_bake.varying(frames) == ["b"]
    assert farm_bake.varying([]) == []
    assert farm_bake.stale_frames({"1": "k1", "2": "k2"}, {1: "k1", 2: "x", 3: "k3"}) == [2, 3]
    assert farm_bake.ranges([1, 2, 3, 7, 9, 10]) == "1-3, 7, 9-10"


def test_record_round_trip_and_other_versions():
    record = {"version": farm_bake.VERSION, "frames": {"1": "k"}}
    assert farm_bake.decode(farm_bake.encode(record)) == record
    assert farm_bake.decode("") is None
    assert farm_bake.decode("not json") is None
    assert farm_bake.decode('{"version": 0}') is None
    assert farm_bake.decode("[1]") is None
