# SPDX-License-Identifier: GPL-3.0-or-later
"""A frame's SceneDescription (docs/pipelines.md "Scene JSON") as plain data, and the files the
aerial-perspective handler writes beside a render. Blender-free: the bpy layer
(blender/aerial/scene.py and pass_files.py) reads the scene and hands plain values here.

Everything the core takes is in metres: Blender's scene units are scaled by
`unit_settings.scale_length` (the camera's translation, orthographic scale and clip range
here; the Z pass in the handler), as docs/pipelines.md "Scene JSON" says.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

# The files of one frame, beside the render: <base>welkin_<kind>_<frame>.<ext>. Blender's
# File Output node appends the frame number (4 digits) to its base path itself.
KINDS = {"render": "exr", "aerial": "exr", "composite": "exr", "scene": "json"}
PASS_CHANNELS = tuple(f"Welkin.Aerial{p}.{c}" for p in ("Inscatter", "Transmittance") for c in "RGB")
COMPOSITE_CHANNELS = ("R", "G", "B")
# With clouds the passes file holds these too (the engine's pass names and channels).
CLOUD_CHANNELS = tuple(f"Welkin.Clouds.{c}" for c in "RGBA") + ("Welkin.CloudDepth.Z",)


def file_base(render_filepath_abs: str) -> str:
    """The prefix of the add-on's files, from the absolute render output path: a
    directory gives `<dir>/`, a file pattern `<dir>/<stem>_` ('#' frame placeholders and
    the extension dropped)."""
    directory, name = os.path.split(render_filepath_abs)
    stem = re.sub(r"#+", "", os.path.splitext(name)[0] if "." in name else name)
    if stem and not stem.endswith(("_", "-", ".")):
        stem += "_"
    return os.path.join(directory, stem)


def frame_path(base: str, kind: str, frame: int) -> str:
    """The path of one of a frame's files (KINDS), frame numbers as Blender writes them."""
    return f"{base}welkin_{kind}_{frame:04d}.{KINDS[kind]}"


def file_output_base(base: str) -> str:
    """The File Output node's base path (Blender appends '0001.exr')."""
    return f"{base}welkin_render_"


def camera_dict(
    matrix_world: Iterable[Iterable[float]],
    cam_type: str,
    lens_mm: float,
    sensor_width_mm: float,
    sensor_height_mm: float,
    sensor_fit: str,
    ortho_scale: float,
    shift_x: float,
    shift_y: float,
    clip_start: float,
    clip_end: float,
    scale_length: float = 1.0,
    panorama: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The scene JSON's camera, in metres. `matrix_world` is a 4x4 list by rows in scene
    units; `panorama` (PANO only) is a dict of panorama_type and the latitude / longitude
    range in degrees."""
    s = float(scale_length)
    m = [[float(v) for v in row] for row in matrix_world]
    for r in range(3):
        m[r][3] *= s
    d: dict[str, Any] = {
        "matrix_world": m,
        "type": cam_type,
        "lens_mm": float(lens_mm),
        "sensor_width_mm": float(sensor_width_mm),
        "sensor_height_mm": float(sensor_height_mm),
        "sensor_fit": sensor_fit,
        "ortho_scale": float(ortho_scale) * s,
        "shift_x": float(shift_x),
        "shift_y": float(shift_y),
        "clip_start_m": float(clip_start) * s,
        "clip_end_m": float(clip_end) * s,
    }
    if cam_type == "PANO" and panorama:
        d.update(panorama)
    return d


def scene_dict(
    atmosphere: str | dict[str, Any],
    origin_altitude_m: float,
    sun_direction: Iterable[float],
    exposure: float,
    method: str,
    camera: dict[str, Any],
    resolution: Sequence[int],
    aerial: Mapping[str, Any] | None = None,
    clouds: dict[str, Any] | None = None,
    color_space: str = "rec709",
) -> dict[str, Any]:
    """The whole scene JSON. `atmosphere` is a preset name or an atmosphere object (dict),
    `resolution` (x, y, percentage), `clouds` the "clouds" section (cloud_export.clouds_dict)
    or None for a clear sky, `color_space` the linear RGB of its colours (rec709, rec2020,
    acescg)."""
    x, y, pct = resolution
    d: dict[str, Any] = {
        "version": 1,
        "atmosphere": atmosphere,
        "origin_altitude_m": float(origin_altitude_m),
        "sun": {"direction": [float(c) for c in sun_direction]},
        "exposure": float(exposure),
        "color_space": color_space,
        "method": method,
        "camera": camera,
        "resolution": {"x": int(x), "y": int(y), "percentage": int(pct)},
    }
    if aerial:
        d["aerial"] = dict(aerial)
    if clouds:
        d["clouds"] = clouds
    return d


def composite(
    image_rgb: npt.NDArray[np.floating],
    inscatter: npt.NDArray[np.floating],
    transmittance: npt.NDArray[np.floating],
    clouds: npt.NDArray[np.floating] | None = None,
) -> npt.NDArray[np.floating]:
    """The hazed render: Image x Transmittance + Inscatter (docs/artists.md "Aerial perspective in Blender"),
    and with clouds (premultiplied RGBA, the air in front of them included) the clouds
    over it: Clouds.rgb + (1 - Clouds.a) x (Image x T + Inscatter)."""
    hazed = image_rgb * transmittance + inscatter
    if clouds is None:
        return hazed
    return clouds[..., :3] + (1.0 - clouds[..., 3:4]) * hazed
