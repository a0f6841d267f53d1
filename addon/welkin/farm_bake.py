# SPDX-License-Identifier: GPL-3.0-or-later
"""Bake for Farm, the part without Blender: what a frame's bake is keyed by, where its
images go, which frame of an image sequence a frame reads, and which node values change
over the frames (blender/farm_bake.py does the baking).

A baked frame is valid while the inputs the add-on computes it from are those it was
baked from: `frame_key` hashes the frame's sky key (everything the world's images and the
lamp depend on: sky_request, the disc and lamp switches, the clouds) and the frame's scene
JSON (camera, sun, atmosphere, render size: what the aerial table depends on), with the
bake's format version. The add-on computes the same key when it renders the frame and
refuses a frame whose key differs (a stale bake).
"""

import hashlib
import json
from typing import Any

VERSION = 1
FOLDER = "welkin_farm"  # beside the .blend: //welkin_farm/<scene>/<role>_NNNN.exr
DIGITS = 4


def frame_key(sky_key: str, scene_json: str, engine: str) -> str:
    """The key of one frame's bake (hex SHA-256): the frame's sky key, its scene JSON and
    the render engine with what else shapes its table (Cycles and EEVEE read different
    tables; Cycles' pixel filter width sets the screen table's margins)."""
    h = hashlib.sha256()
    for part in (f"welkin-farm-bake/{VERSION}", engine, sky_key, scene_json):
        data = part.encode("utf-8")
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()


def safe_name(name: str) -> str:
    """A file-name-safe form of a scene's or an image's name (letters, digits, '-', '_')."""
    out = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)
    return out or "_"


def sequence_path(scene_name: str, role: str, index: int) -> str:
    """The .blend-relative path of image `role`'s file for sequence index `index` (1-based),
    as Blender names a sequence's frames: the digits at the end of the name are the frame."""
    if index < 1:
        raise ValueError(f"index must be at least 1, got {index}")
    return f"//{FOLDER}/{safe_name(scene_name)}/{safe_name(role)}_{index:0{DIGITS}d}.exr"


def frames_of(frame_start: int, frame_end: int) -> list[int]:
    """Every frame of the scene's range (a farm may render any of them with its own -j)."""
    if frame_end < frame_start:
        raise ValueError(f"frame_end ({frame_end}) must not be before frame_start ({frame_start})")
    return list(range(frame_start, frame_end + 1))


def image_user(frame_start: int, frame_end: int) -> dict[str, int]:
    """The image user settings that make a sequence of files 1..N play frame_start..frame_end
    (Blender's image user: number = frame - start + 1 clamped to 1..duration, + offset)."""
    return {"frame_start": frame_start, "frame_duration": frame_end - frame_start + 1, "frame_offset": 0}


def varying(values_per_frame: list[dict[str, Any]]) -> list[str]:
    """The names whose value is not the same on every frame. `values_per_frame`: a list of
    {name: value} (floats or tuples of floats), one per frame, with the same names."""
    if not values_per_frame:
        return []
    first = values_per_frame[0]
    return sorted(name for name in first if any(v[name] != first[name] for v in values_per_frame[1:]))


def stale_frames(stored: dict[str, str], current: dict[int, str]) -> list[int]:
    """The frames of `current` ({frame: key}) whose key is not the stored one."""
    return sorted(f for f, key in current.items() if stored.get(str(f)) != key)


def ranges(frames: list[int]) -> str:
    """'1-3, 7' for [1, 2, 3, 7] (sorted frames)."""
    parts: list[list[int]] = []
    for f in frames:
        if parts and f == parts[-1][1] + 1:
            parts[-1][1] = f
        else:
            parts.append([f, f])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in parts)


def encode(record: dict[str, Any]) -> str:
    return json.dumps(record, sort_keys=True)


def decode(text: str) -> dict[str, Any] | None:
    """The stored bake record, or None (no bake, or an unreadable one)."""
    if not text:
        return None
    try:
        record = json.loads(text)
    except ValueError:
        return None
    if not isinstance(record, dict) or record.get("version") != VERSION:
        return None
    return record
