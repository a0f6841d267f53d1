"""Pixel layouts: the core and EXR files store images top row first (row 0 at the
zenith); Blender's Image.pixels are bottom row first, RGBA. The flip happens here, once.
"""
import numpy as np


def to_blender(image):
    """(H, W, 3) top-row-first -> flat float32 RGBA, bottom row first (alpha 1)."""
    h, w, c = image.shape
    out = np.empty((h, w, 4), dtype=np.float32)
    out[..., :3] = image[::-1, :, :3]
    out[..., 3] = 1.0
    return out.reshape(-1)


def from_blender(flat, width, height):
    """Blender's flat RGBA pixels -> (H, W, 3) float32, top row first."""
    return np.asarray(flat, dtype=np.float32).reshape(height, width, 4)[::-1, :, :3].copy()
