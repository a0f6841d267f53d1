# SPDX-License-Identifier: GPL-3.0-or-later
"""The render engine's plate, Blender-free: the scene description it renders, and the
passes as Blender's render result wants them.

The Welkin render engine (blender/engine/render_engine.py) renders the active camera's plate:
sky, sun disc and aerial perspective over the ground, no meshes. The core computes it
(`welkin.camera_plate`, camera_plate.hpp); this module only writes the scene description
(docs/pipelines.md "Scene JSON") from plain values read off bpy, and reshapes the core's arrays
(top row first, RGB) into Blender's pass rectangles (bottom row first, RGBA or RGB).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from types import ModuleType
from typing import TYPE_CHECKING, Any

from . import scene_export

if TYPE_CHECKING:
    import numpy
    import numpy.typing as npt

# Pass name -> (channels, Blender chan_id, the plate array it comes from). A scene without
# clouds has no "clouds" / "cloud_depth" arrays: Clouds is then transparent black and
# CloudDepth NO_CLOUD_DEPTH, as where a cloudy plate has no cloud.
PASSES = (
    ("Welkin.Sky", 4, "RGBA", "sky"),
    ("Welkin.AerialInscatter", 3, "RGB", "inscatter"),
    ("Welkin.AerialTransmittance", 3, "RGB", "transmittance"),
    ("Welkin.Clouds", 4, "RGBA", "clouds"),
    ("Welkin.CloudDepth", 1, "Z", "cloud_depth"),
)
# Welkin.CloudDepth where no cloud: what Cycles writes for the background, so the pass
# Z-combines with Blender's Z pass (the clouds schema).
NO_CLOUD_DEPTH = 1e10
PASS_NAMES = tuple(p[0] for p in PASSES)


def camera_dict(
    matrix_rows: Iterable[Iterable[float]], data: Mapping[str, Any], scale_length: float = 1.0
) -> dict[str, Any]:
    """The scene JSON's "camera" from an object's matrix_world (4 rows) and a dict of the
    Camera data's values (type, lens, sensor_*, ortho_scale, shift_*, clip_*, and for
    panoramas panorama_type and the latitude/longitude range in radians); the JSON itself
    is scene_export.camera_dict's."""
    panorama: dict[str, Any] | None = None
    if data["type"] == "PANO":
        panorama = {"panorama_type": data.get("panorama_type", "EQUIRECTANGULAR")}
        for key in ("latitude_min", "latitude_max", "longitude_min", "longitude_max"):
            panorama[key + "_deg"] = math.degrees(float(data[key]))
    return scene_export.camera_dict(
        matrix_rows,
        data["type"],
        data["lens"],
        data["sensor_width"],
        data["sensor_height"],
        data["sensor_fit"],
        data["ortho_scale"],
        data["shift_x"],
        data["shift_y"],
        data["clip_start"],
        data["clip_end"],
        scale_length=scale_length,
        panorama=panorama,
    )


def scene_json(
    atmosphere_json: str,
    origin_altitude_m: float,
    sun_direction: Iterable[float],
    exposure: float,
    method: str,
    camera: dict[str, Any],
    resolution: Sequence[int],
    clouds: dict[str, Any] | None = None,
    color_space: str = "rec709",
) -> str:
    """The scene description's JSON text (scene_export.scene_dict's). `atmosphere_json`:
    Atmosphere.to_json_string() (written in full, so the file reproduces the frame);
    `resolution`: (x, y, percentage); `color_space`: of the passes (the working space)."""
    return json.dumps(
        scene_export.scene_dict(
            json.loads(atmosphere_json),
            origin_altitude_m,
            sun_direction,
            exposure,
            method,
            camera,
            resolution,
            clouds=clouds,
            color_space=color_space,
        )
    )


def pass_rect(
    np: ModuleType, plate: Mapping[str, Any], source: str, channels: int, rows: Sequence[int] | None = None
) -> npt.NDArray[numpy.float32]:
    """One pass as Blender's rect: (n, channels) float32, bottom row first, for the plate's
    rows [r0, r1) counted from the top (`rows`, default all). A `source` the plate lacks
    (the cloud passes of a clear sky): 0 colour and alpha; depth NO_CLOUD_DEPTH."""
    height, width = plate["depth"].shape
    r0, r1 = rows or (0, height)
    n = (r1 - r0) * width
    if source not in plate:
        fill = NO_CLOUD_DEPTH if channels == 1 else 0.0
        return np.full((n, channels), fill, dtype=np.float32)
    array = np.asarray(plate[source])
    if array.ndim == 2:
        array = array[..., None]
    if array.shape[-1] == channels:
        return np.ascontiguousarray(array[r0:r1][::-1].reshape(n, channels), dtype=np.float32)
    rgb = array[r0:r1][::-1].reshape(n, 3)
    if channels == 3:
        return np.ascontiguousarray(rgb, dtype=np.float32)
    out = np.ones((n, 4), dtype=np.float32)
    out[:, :3] = rgb
    return out


def bands(height: int, band_rows: int) -> Iterator[tuple[tuple[int, int], int, int]]:
    """Row bands [r0, r1) from the bottom of the image up (the order Blender shows them),
    as (rows from the top, Blender's y of the band's bottom row, band height)."""
    y = 0
    while y < height:
        h = min(band_rows, height - y)
        yield (height - y - h, height - y), y, h
        y += h
