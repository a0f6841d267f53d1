"""The render engine's plate, Blender-free: the scene description it renders, and the
passes as Blender's render result wants them.

The Welkin render engine (blender/render_engine.py) renders the active camera's plate:
sky, sun disc and aerial perspective over the ground, no meshes. The core computes it
(`welkin.camera_plate`, camera_plate.hpp); this module only writes the scene description
(README "Scene JSON") from plain values read off bpy, and reshapes the core's arrays
(top row first, RGB) into Blender's pass rectangles (bottom row first, RGBA or RGB).
"""
import json
import math

# Pass name -> (channels, Blender chan_id, the plate array it comes from or None when the
# pass is empty until clouds land: Clouds is transparent black, CloudDepth +infinity).
PASSES = (
    ("Welkin.Sky", 4, "RGBA", "sky"),
    ("Welkin.AerialInscatter", 3, "RGB", "inscatter"),
    ("Welkin.AerialTransmittance", 3, "RGB", "transmittance"),
    ("Welkin.Clouds", 4, "RGBA", None),
    ("Welkin.CloudDepth", 1, "Z", None),
)
PASS_NAMES = tuple(p[0] for p in PASSES)


def camera_dict(matrix_rows, data, scale_length=1.0):
    """The scene JSON's "camera" from an object's matrix_world (4 rows) and a dict of the
    Camera data's values (type, lens, sensor_*, ortho_scale, shift_*, clip_*, and for
    panoramas panorama_type and the latitude/longitude range in radians)."""
    rows = [[float(v) for v in row] for row in matrix_rows]
    for r in range(3):
        rows[r][3] *= scale_length
    cam = {
        "matrix_world": rows,
        "type": data["type"],
        "lens_mm": float(data["lens"]),
        "sensor_width_mm": float(data["sensor_width"]),
        "sensor_height_mm": float(data["sensor_height"]),
        "sensor_fit": data["sensor_fit"],
        "ortho_scale": float(data["ortho_scale"]) * scale_length,
        "shift_x": float(data["shift_x"]),
        "shift_y": float(data["shift_y"]),
        "clip_start_m": float(data["clip_start"]) * scale_length,
        "clip_end_m": float(data["clip_end"]) * scale_length,
    }
    if data["type"] == "PANO":
        cam["panorama_type"] = data.get("panorama_type", "EQUIRECTANGULAR")
        for key in ("latitude_min", "latitude_max", "longitude_min", "longitude_max"):
            cam[key + "_deg"] = math.degrees(float(data[key]))
    return cam


def scene_json(atmosphere_json, origin_altitude_m, sun_direction, exposure, method, camera,
               resolution):
    """The scene description's JSON text. `atmosphere_json`: Atmosphere.to_json_string()
    (written in full, so the file reproduces the frame); `resolution`: (x, y, percentage)."""
    x, y, percentage = resolution
    return json.dumps({
        "version": 1,
        "atmosphere": json.loads(atmosphere_json),
        "origin_altitude_m": float(origin_altitude_m),
        "sun": {"direction": [float(c) for c in sun_direction]},
        "exposure": float(exposure),
        "method": method,
        "camera": camera,
        "resolution": {"x": int(x), "y": int(y), "percentage": int(percentage)},
    })


def pass_rect(np, plate, source, channels, rows=None):
    """One pass as Blender's rect: (n, channels) float32, bottom row first, for the plate's
    rows [r0, r1) counted from the top (`rows`, default all). `source` None: the empty
    cloud passes (0 colour and alpha; depth +infinity)."""
    height, width = plate["depth"].shape
    r0, r1 = rows or (0, height)
    n = (r1 - r0) * width
    if source is None:
        fill = math.inf if channels == 1 else 0.0
        return np.full((n, channels), fill, dtype=np.float32)
    rgb = plate[source][r0:r1][::-1].reshape(n, 3)
    if channels == 3:
        return np.ascontiguousarray(rgb, dtype=np.float32)
    out = np.ones((n, 4), dtype=np.float32)
    out[:, :3] = rgb
    return out


def bands(height, band_rows):
    """Row bands [r0, r1) from the bottom of the image up (the order Blender shows them),
    as (rows from the top, Blender's y of the band's bottom row, band height)."""
    y = 0
    while y < height:
        h = min(band_rows, height - y)
        yield (height - y - h, height - y), y, h
        y += h
