# SPDX-License-Identifier: GPL-3.0-or-later
"""Pixel layouts: the core and EXR files store images top row first (row 0 at the
zenith); Blender's Image.pixels are bottom row first, RGBA. The flip happens here, once.

Live updates at 2048 x 1024 move 8 M floats per image, so the RGBA buffers can be kept and
reused (`out`): a fresh 32 MiB array costs its page faults every time.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def rgba_buffer(width: int, height: int) -> npt.NDArray[np.float32]:
    """A bottom-row-first RGBA buffer, zero with alpha 1, shape (H, W, 4)."""
    out = np.zeros((height, width, 4), dtype=np.float32)
    out[..., 3] = 1.0
    return out


def to_blender(
    image: npt.NDArray[np.floating], out: npt.NDArray[np.float32] | None = None
) -> npt.NDArray[np.float32]:
    """(H, W, 3) top-row-first -> flat float32 RGBA, bottom row first (alpha 1). Writes
    into `out` ((H, W, 4) float32, alpha already 1) when given."""
    h, w, _ = image.shape
    if out is None:
        out = rgba_buffer(w, h)
    out[..., :3] = image[::-1, :, :3]
    return out.reshape(-1)


def from_blender(flat: npt.ArrayLike, width: int, height: int) -> npt.NDArray[np.float32]:
    """Blender's flat RGBA pixels -> (H, W, 3) float32, top row first."""
    return np.asarray(flat, dtype=np.float32).reshape(height, width, 4)[::-1, :, :3].copy()
