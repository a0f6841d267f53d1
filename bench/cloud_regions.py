# SPDX-License-Identifier: Apache-2.0
"""The regions of a rendered cloud that the Cycles comparisons read (bench/cycles_addon_clouds.py,
bench/clouds/sun_light_per_type.py), from the image alone: no Blender needed."""

import numpy as np


def image_regions(alpha, sun_x, sun_y):
    """Masks over the cloud's pixels (alpha > 0.05) of an (H, W) opacity image: "all";
    "sunlit", the half of them towards the sun, (sun_x, sun_y) being the sun's direction
    projected on the image's right and up axes; "shadow", the other half; "base", the bottom
    fifth of the cloud's rows; "edge" (0.05 < alpha < 0.6) and "core" (alpha > 0.95)."""
    h, w = alpha.shape
    mask = alpha > 0.05
    yy, xx = np.mgrid[0:h, 0:w].astype(float)
    toward = (xx - xx[mask].mean()) * sun_x - (yy - yy[mask].mean()) * sun_y  # rows grow downwards
    sunlit = mask & (toward > np.median(toward[mask]))
    rows = np.nonzero(mask.any(axis=1))[0]
    return {
        "all": mask,
        "sunlit": sunlit,
        "shadow": mask & ~sunlit,
        "base": mask & (yy >= rows.min() + 0.8 * (rows.max() - rows.min() + 1)),
        "edge": mask & (alpha < 0.6),
        "core": alpha > 0.95,
    }
