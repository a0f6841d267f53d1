# SPDX-License-Identifier: GPL-3.0-or-later
"""Night vision for display: the numbers of the compositor group "Welkin Night Vision"
(blender/sky/night_vision.py builds it from stock nodes). Nothing here reads bpy.

The rendered frame holds physical radiance: a camera's record of the night, in colour.
The dark-adapted eye sees it otherwise: with its rods, in little colour, a little blue,
and with less detail. Jensen, Durand, Stark, Premoze, Dorsey and Shirley, "A
Physically-Based Night Sky Model" (SIGGRAPH 2001), in their section on tone mapping, map a
physical image to what the eye sees at night in three steps, which the group applies to
each pixel of the frame as it reaches the compositor's output (the frame in the render
layer, the passes and the world keep their physical values):

1. Luminances. The pixel's CIE XYZ from its linear RGB in the working colour space
   (rgb_to_xyz below), in the frame's units: Welkin's radiance is CIE-weighted without
   the 683 lm/W factor (docs/design.md, "Conventions"), so the photopic luminance in
   cd/m^2 is L = k Y with k = 683 / exposure (the sky's Exposure setting). The scotopic
   luminance, Jensen 2001 after Ward Larson, Rushmeier and Piatko (1997), "A visibility
   matching tone reproduction operator", IEEE TVCG 3(4):
       V = Y [1.33 (1 + (Y + Z) / X) - 1.68]                       (clamped at 0)
2. Mesopic blend. A weight s from the luminance's logarithm, a smoothstep over the
   mesopic range 10^-2 to 10^0.6 cd/m^2 (rods alone below, cones alone above):
       t = clamp((log10 L + 2) / 2.6, 0, 1),  s = 3 t^2 - 2 t^3
   blends the pixel's chromaticity (x, y) = (X, Y) / (X + Y + Z) with the rods' blue
   shift (x_b, y_b) = (0.25, 0.25), and its luminance with the scaled scotopic one:
       x' = (1 - s) x_b + s x,  y' = (1 - s) y_b + s y,
       Y' = (1 - s) 0.4468 V + s Y,
       X' = x' Y' / y',  Z' = (1 - x' - y') Y' / y'
   back to RGB in the working space, in the frame's units. At s = 1 (photopic) the pixel
   is unchanged; at s = 0 it is a blue-grey of luminance 0.4468 V.
3. Loss of acuity. The eye resolves at most R(L) cycles per degree, Ward Larson et al.
   1997's fit to Shaler's (1937) data:
       R(L) = 17.25 arctan(1.4 log10 L + 0.35) + 25.72
   (about 47 c/deg at 100 cd/m^2, 5.3 at the scotopic limit 10^-2 cd/m^2). Welkin's
   simplification: the mapped frame is blurred once, with a Gaussian of radius one
   period of the finest grating seen at 10^-2 cd/m^2 (acuity_blur_px: pixels per degree
   of the camera / R(10^-2)), and each pixel takes the blurred frame with the weight
   (1 - s): no blur where it is photopic, all of it where it is scotopic, so that the
   blur grows as it gets darker.

The blue shift's chromaticity (0.25, 0.25), the mesopic range, the smoothstep and the
0.4468 scale are Jensen 2001's (the same numbers as Stellarium's sky shader, which cites
it). The output is still scene-referred: expose it (Render > Color Management) as the
physical frame.
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]

# Step 2's constants.
BLUE_SHIFT_XY = (0.25, 0.25)
MESOPIC_LOG10_CD_M2 = (-2.0, 0.6)  # log10 of the luminance where s goes from 0 to 1
SCOTOPIC_SCALE = 0.4468
# Step 1: V's coefficients.
V_A, V_B = 1.33, 1.68
# Welkin's radiance to cd/m^2 (docs/design.md "Conventions").
LUMENS_PER_WATT = 683.0
# The luminance below which the logarithm is not taken (cd/m^2): far below any night
# sky (about 2e-4 cd/m^2 moonless), so black stays black (s = 0, V = 0).
LUMINANCE_FLOOR = 1e-12
# Step 3: where the acuity blur is sized.
ACUITY_LUMINANCE_CD_M2 = 1e-2

# Primaries and white (CIE 1931 xy) of the working spaces Blender offers (compat.
# working_color_space): Rec.709 (IEC 61966-2-1), Rec.2020 (ITU-R BT.2020), ACEScg (AP1,
# ACES white; SMPTE ST 2065-1), as include/welkin/color/color_space.hpp takes them.
_SPACES: dict[str, tuple[tuple[tuple[float, float], ...], tuple[float, float]]] = {
    "rec709": (((0.64, 0.33), (0.30, 0.60), (0.15, 0.06)), (0.3127, 0.3290)),
    "rec2020": (((0.708, 0.292), (0.170, 0.797), (0.131, 0.046)), (0.3127, 0.3290)),
    "acescg": (((0.713, 0.293), (0.165, 0.830), (0.128, 0.044)), (0.32168, 0.33767)),
}
_D65 = (0.3127, 0.3290)
# Bradford's cone response matrix (Lam 1985), for ACEScg's white to D65, as the core does.
_BRADFORD: Mat3 = ((0.8951, 0.2664, -0.1614), (-0.7502, 1.7135, 0.0367), (0.0389, -0.0685, 1.0296))


def _xyz(xy: tuple[float, float]) -> Vec3:
    x, y = xy
    return (x / y, 1.0, (1.0 - x - y) / y)


def _mul(a: Mat3, b: Mat3) -> Mat3:
    r0, r1, r2 = (_apply(a, (b[0][j], b[1][j], b[2][j])) for j in range(3))
    return ((r0[0], r1[0], r2[0]), (r0[1], r1[1], r2[1]), (r0[2], r1[2], r2[2]))


def _apply(m: Mat3, v: Vec3) -> Vec3:
    x, y, z = (sum(m[i][k] * v[k] for k in range(3)) for i in range(3))
    return (x, y, z)


def inverse(m: Mat3) -> Mat3:
    """The inverse of a 3 x 3 matrix (tuples of rows)."""
    (a, b, c), (d, e, f), (g, h, i) = m
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    adj = (
        (e * i - f * h, c * h - b * i, b * f - c * e),
        (f * g - d * i, a * i - c * g, c * d - a * f),
        (d * h - e * g, b * g - a * h, a * e - b * d),
    )
    (a, b, c), (d, e, f), (g, h, i) = adj
    return ((a / det, b / det, c / det), (d / det, e / det, f / det), (g / det, h / det, i / det))


def rgb_to_xyz(color_space: str = "rec709") -> Mat3:
    """The matrix from linear RGB in `color_space` ("rec709", "rec2020", "acescg") to CIE
    XYZ seen under D65 (rows X, Y, Z): the primaries scaled so that RGB (1, 1, 1) is the
    space's white with Y = 1 (SMPTE RP 177), and for ACEScg Bradford's adaptation from the
    ACES white to D65."""
    if color_space not in _SPACES:
        raise ValueError(f"color_space: {color_space!r} is not one of {sorted(_SPACES)}")
    primaries, white = _SPACES[color_space]
    c0, c1, c2 = (_xyz(p) for p in primaries)
    p: Mat3 = ((c0[0], c1[0], c2[0]), (c0[1], c1[1], c2[1]), (c0[2], c1[2], c2[2]))
    k = _apply(inverse(p), _xyz(white))
    r0, r1, r2 = ((row[0] * k[0], row[1] * k[1], row[2] * k[2]) for row in p)
    m: Mat3 = (r0, r1, r2)
    if white == _D65:
        return m
    src, dst = _apply(_BRADFORD, _xyz(white)), _apply(_BRADFORD, _xyz(_D65))
    gain: Mat3 = ((dst[0] / src[0], 0.0, 0.0), (0.0, dst[1] / src[1], 0.0), (0.0, 0.0, dst[2] / src[2]))
    adapt = _mul(inverse(_BRADFORD), _mul(gain, _BRADFORD))
    return _mul(adapt, m)


def luminance_scale(exposure: float) -> float:
    """cd/m^2 per unit of the frame's Y: 683 lm/W over the sky's Exposure setting."""
    if not exposure > 0.0 or not math.isfinite(exposure):
        raise ValueError(f"exposure: {exposure} must be a finite number > 0")
    return LUMENS_PER_WATT / exposure


def acuity_cycles_per_degree(luminance_cd_m2: float) -> float:
    """R(L): the finest grating the eye resolves at luminance L, cycles per degree (Ward
    Larson, Rushmeier and Piatko 1997, after Shaler 1937)."""
    return 17.25 * math.atan(1.4 * math.log10(luminance_cd_m2) + 0.35) + 25.72


def acuity_blur_px(pixels_per_degree: float) -> float:
    """The acuity blur's radius in pixels for an image of `pixels_per_degree`: one period
    of the finest grating seen at ACUITY_LUMINANCE_CD_M2 (10^-2 cd/m^2, the scotopic
    limit: 5.3 cycles per degree)."""
    if not pixels_per_degree >= 0.0 or not math.isfinite(pixels_per_degree):
        raise ValueError(f"pixels_per_degree: {pixels_per_degree} must be a finite number >= 0")
    return pixels_per_degree / acuity_cycles_per_degree(ACUITY_LUMINANCE_CD_M2)


def pixels_per_degree(
    camera_type: str, angle_x_rad: float, width_px: float, longitude_range_rad: float | None = None
) -> float:
    """Pixels per degree across the frame for the scene camera: a perspective camera's
    horizontal angle, a panorama's longitude range; 0 for an orthographic camera (no
    angle: no blur)."""
    if camera_type == "PERSP" and angle_x_rad > 0.0:
        return width_px / math.degrees(angle_x_rad)
    if camera_type == "PANO" and longitude_range_rad:
        return width_px / math.degrees(longitude_range_rad)
    return 0.0
