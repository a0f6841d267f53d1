# SPDX-License-Identifier: GPL-3.0-or-later
"""The scene JSON's "clouds" section (docs/artists.md "Clouds in Blender", /work notes' schema) as
plain data, and the frame rule of Blender's VDB sequences. Blender-free: the bpy layer
(blender/clouds/scene.py) reads the world's cloud layers and the marked volume objects and
hands plain values here; the core validates every field (and names it when it refuses).

A volume object's file for a frame follows Blender's own sequence rule (the rule of
`Volume.grids.frame_filepath`, Blender's volume.cc): with a sequence, the scene frame f
maps to the file frame
    n = f - frame_start + 1, then by sequence_mode, for d = frame_duration:
        CLIP       n outside [1, d]: no volume at this frame (Blender hides it)
        EXTEND     n clamped to [1, d]
        REPEAT     n mod d in [1, d]
        PING_PONG  n mod (2d - 2) in [1, 2d - 2], mirrored beyond d
    n += frame_offset,
and the last run of digits in the file name is replaced by n, zero-padded to that run's
width (`cloud.0001.vdb` -> `cloud.0007.vdb`). A file without digits, or no sequence, is
used as it is at every frame.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

# The layer fields of the schema, with the core's defaults (clouds/procedural.hpp,
# CloudLayerParams); planet radius and origin altitude come from the scene.
# cloud_type is a preset name (CLOUD_TYPES), coverage_measure what coverage measures
# (COVERAGE_MEASURES: the sky dome a ground observer sees covered, oktas / 8, or the ground's
# area under cloud); the others are numbers.
CLOUD_TYPES = ("cumulus", "stratocumulus", "altocumulus", "stratus", "cirrus")
COVERAGE_MEASURES = ("dome", "area")
# The most cloud layers a scene holds (the core's SceneClouds::kMaxLayers, scene/clouds.hpp).
MAX_LAYERS = 32
LAYER_FIELDS = (
    "cloud_type",
    "bottom_altitude_m",
    "top_altitude_m",
    "coverage",
    "coverage_measure",
    "density_per_m",
    "base_scale_m",
    "detail_scale_m",
    "weather_scale_m",
    "detail_strength",
    "weather_variation",
    "evolution_m",
)
# The lighting fields the panel offers (clouds/lighting.hpp, CloudLightingOptions).
LIGHTING_FIELDS = ("max_steps", "light_steps", "ambient_steps", "octaves")

SEQUENCE_MODES = ("CLIP", "EXTEND", "REPEAT", "PING_PONG")
_DIGITS = re.compile(r"(\d+)(?!.*\d)")


class MissingVolume(Exception):
    """A marked volume object whose file for the frame is absent; names object and path."""


def sequence_frame(
    frame: float, frame_start: float, frame_offset: float, frame_duration: float, mode: str
) -> int | None:
    """The file frame number for scene `frame`, or None when the sequence shows nothing
    there (CLIP outside its range, or a duration of 0)."""
    if mode not in SEQUENCE_MODES:
        raise ValueError(f"sequence_mode: must be one of {', '.join(SEQUENCE_MODES)}, got {mode!r}")
    d = int(frame_duration)
    if d <= 0:
        return None
    n = int(frame) - int(frame_start) + 1
    if mode == "CLIP":
        if n < 1 or n > d:
            return None
    elif mode == "EXTEND":
        n = min(max(n, 1), d)
    elif mode == "REPEAT":
        n %= d
        if n == 0:
            n = d
    else:  # PING_PONG
        period = 2 * d - 2
        if period <= 0:
            n = 1
        else:
            n %= period
            if n == 0:
                n = period
            if n > d:
                n = 2 * d - n
    return n + int(frame_offset)


def frame_filepath(filepath: str, n: int) -> str:
    """`filepath` with the last run of digits in its file name replaced by `n` (zero-padded
    to the run's width); unchanged when the name has no digits."""
    directory, name = os.path.split(filepath)
    match = _DIGITS.search(name)
    if match is None:
        return filepath
    width = len(match.group(1))
    digits = f"{n:0{width}d}" if n >= 0 else f"-{-n:0{width}d}"
    return os.path.join(directory, name[: match.start(1)] + digits + name[match.end(1) :])


def volume_file(
    filepath_abs: str,
    is_sequence: bool,
    frame: float,
    frame_start: float = 1,
    frame_offset: float = 0,
    frame_duration: float = 0,
    mode: str = "CLIP",
) -> str | None:
    """The VDB file a volume shows at scene `frame`, or None where its sequence shows
    nothing."""
    if not is_sequence:
        return filepath_abs
    n = sequence_frame(frame, frame_start, frame_offset, frame_duration, mode)
    return None if n is None else frame_filepath(filepath_abs, n)


def layer_dict(values: Mapping[str, Any], seed: int, wind_offset_m: Sequence[float]) -> dict[str, Any]:
    """One procedural layer: `values` maps LAYER_FIELDS to numbers (cloud_type to one of
    CLOUD_TYPES, coverage_measure to one of COVERAGE_MEASURES, any case; a missing
    coverage_measure is the core's default, "dome"). ValueError naming the field for a number
    that is not finite (JSON has no NaN or infinity; the core checks every range and name)."""
    names = ("cloud_type", "coverage_measure")
    d: dict[str, Any] = {k: float(values[k]) for k in LAYER_FIELDS if k not in names}
    d["cloud_type"] = str(values["cloud_type"]).lower()
    d["coverage_measure"] = str(values.get("coverage_measure", "dome")).lower()
    d["wind_offset_m"] = [float(wind_offset_m[0]), float(wind_offset_m[1])]
    named = [(k, v) for k, v in d.items() if k not in names and k != "wind_offset_m"]
    named += [(f"wind_offset_m[{i}]", v) for i, v in enumerate(d["wind_offset_m"])]
    for name, v in named:
        if not math.isfinite(v):
            raise ValueError(f"{name}: must be a finite number, got {v}")
    d["seed"] = int(seed)
    return d


def volume_dict(
    name: str,
    path: str,
    grid: str,
    matrix_world: Iterable[Iterable[float]],
    density_scale: float,
    scale_length: float = 1.0,
    placement: str = "blender",
) -> dict[str, Any]:
    """One VDB volume. `matrix_world` by rows in scene units (its translation is scaled to
    metres); `placement`: where the Blender that shows it puts voxel ijk ("blender",
    "openvdb": VdbClouds); raises MissingVolume when the file is absent."""
    if not os.path.isfile(path):
        raise MissingVolume(f"volume object '{name}': its VDB file for this frame is missing: {path}")
    s = float(scale_length)
    m = [[float(v) for v in row] for row in matrix_world]
    for r in range(3):
        for c in range(4):
            m[r][c] *= s  # the whole placement (voxel size too) from scene units to metres
    return {
        "name": name,
        "file": path,
        "grid": grid,
        "matrix_world": m,
        "density_scale": float(density_scale),
        "negative": "clamp",
        "placement": placement,
    }


def clouds_dict(
    layers: Iterable[Mapping[str, Any]],
    volumes: Iterable[Mapping[str, Any]],
    albedo: float,
    lighting: Mapping[str, float],
) -> dict[str, Any] | None:
    """The "clouds" section, or None when there is nothing to render (a clear sky)."""
    if not layers and not volumes:
        return None
    return {
        "layers": list(layers),
        "volumes": list(volumes),
        "scattering": {"albedo": float(albedo)},
        "lighting": {k: int(lighting[k]) for k in LIGHTING_FIELDS},
    }
