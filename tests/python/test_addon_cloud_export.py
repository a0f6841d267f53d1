# SPDX-License-Identifier: Apache-2.0
"""The add-on's Blender-free clouds section (addon/welkin/cloud_export.py): Blender's VDB
sequence rule written out by hand from its definition (frame n = f - start + 1, then the
mode, then the offset; the last digits of the name replaced, zero-padded), the volume's
placement in metres, a missing file refused naming object and path. The rule is checked
against Blender's own Volume.grids.frame_filepath in tests/blender/test_cloud_export.py."""

import pytest

from welkin_addon import cloud_export


@pytest.mark.parametrize(
    "mode,frames",
    [
        ("CLIP", [None, None, 1, 2, 3, 4, None, None]),
        ("EXTEND", [1, 1, 1, 2, 3, 4, 4, 4]),
        ("REPEAT", [3, 4, 1, 2, 3, 4, 1, 2]),  # period 4, scene frame 3 -> 1
        ("PING_PONG", [3, 2, 1, 2, 3, 4, 3, 2]),  # period 6: 1 2 3 4 3 2
    ],
)
def test_sequence_modes(mode, frames):
    # Start at scene frame 3, 4 files: scene frames 1..8.
    got = [cloud_export.sequence_frame(f, 3, 0, 4, mode) for f in range(1, 9)]
    assert got == frames


def test_offset_and_empty_sequence():
    assert cloud_export.sequence_frame(5, 1, 10, 8, "CLIP") == 15
    assert cloud_export.sequence_frame(5, 1, 0, 0, "EXTEND") is None
    with pytest.raises(ValueError, match="sequence_mode"):
        cloud_export.sequence_frame(1, 1, 0, 3, "LOOP")


def test_frame_filepath_replaces_the_last_digits():
    assert cloud_export.frame_filepath("/a/b2/cloud_0001.vdb", 17) == "/a/b2/cloud_0017.vdb"
    assert cloud_export.frame_filepath("/a/v3.1.vdb", 12) == "/a/v3.12.vdb"
    assert cloud_export.frame_filepath("/a/cloud.vdb", 5) == "/a/cloud.vdb"
    assert cloud_export.volume_file("/a/c_01.vdb", False, 9) == "/a/c_01.vdb"
    assert cloud_export.volume_file("/a/c_01.vdb", True, 9, 1, 0, 3, "CLIP") is None
    assert cloud_export.volume_file("/a/c_01.vdb", True, 2, 1, 0, 3, "CLIP") == "/a/c_02.vdb"


def test_volume_dict(tmp_path):
    f = tmp_path / "c.vdb"
    f.write_bytes(b"")
    m = [[2, 0, 0, 10], [0, 2, 0, 20], [0, 0, 2, 30], [0, 0, 0, 1]]
    d = cloud_export.volume_dict("Cloud", str(f), "density", m, 0.5, scale_length=0.01)
    assert d["matrix_world"][0] == pytest.approx([0.02, 0, 0, 0.1])
    assert d["matrix_world"][3] == [0, 0, 0, 1]
    assert d["file"] == str(f) and d["negative"] == "clamp" and d["density_scale"] == 0.5
    assert d["placement"] == "blender"  # the core's default, Cycles 3.4-4.5's placement
    d = cloud_export.volume_dict("Cloud", str(f), "density", m, 0.5, placement="openvdb")
    assert d["placement"] == "openvdb"
    with pytest.raises(cloud_export.MissingVolume, match="'Cloud'.*gone.vdb"):
        cloud_export.volume_dict("Cloud", str(tmp_path / "gone.vdb"), "density", m, 1.0)
    assert cloud_export.clouds_dict([], [], 1.0, {}) is None
