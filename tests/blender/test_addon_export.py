# SPDX-License-Identifier: Apache-2.0
"""welkin.export_hdri: the EXR holds the module's HDRI for the scene's sun (float exactly;
half within half precision, 2^-11 relative, with the disc clamped to 65504 and reported),
the world's resolution by default, and an existing file is never replaced unless
overwrite=True; bad widths and paths are refused with a report."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
scene, sun = T.new_scene(35.0, 120.0, resolution="256")
bpy.ops.welkin.update_sky()
atm = welkin.Atmosphere.preset(welkin.Atmosphere.preset_names()[0])  # the add-on's default
s = tuple(sun.matrix_world.col[2][:3])  # the lamp's own direction, as the add-on reads it

path = T.TMP / "export.exr"
bpy.ops.welkin.export_hdri(filepath=str(path))  # width 0: the world's 256
img = T.read_rgb_exr(welkin, path)
ref = welkin.sky_image(atm, 0.0, s, 256, "auto")  # with the disc; the add-on's default method
T.check(img.shape == (128, 256, 3), f"shape {img.shape}")
T.check(np.allclose(img, ref, rtol=1e-6, atol=0.0), "float HDRI differs from sky_image")
print("float HDRI equals welkin.sky_image for the scene's sun")

# Never overwritten unless asked.
mtime, size = os.path.getmtime(path), os.path.getsize(path)
try:
    bpy.ops.welkin.export_hdri(filepath=str(path), width=64)
    raise AssertionError("export_hdri replaced an existing file")
except RuntimeError as error:
    T.check("exists" in str(error) and "overwrite" in str(error), str(error))
T.check((os.path.getmtime(path), os.path.getsize(path)) == (mtime, size), "file touched")

bpy.ops.welkin.export_hdri(filepath=str(path), width=64, half=True, overwrite=True)
img = T.read_rgb_exr(welkin, path)
ref = welkin.sky_image(atm, 0.0, s, 64, "auto")
T.check(img.shape == (32, 64, 3), f"shape {img.shape}")
unclamped = ref < 65504.0
T.check(
    np.allclose(img[unclamped], ref[unclamped], rtol=2.0**-11, atol=0.0),
    "half HDRI differs beyond half precision",
)
T.check(np.all(img[~unclamped] == 65504.0), "disc values not clamped to 65504")
print(f"half HDRI within half precision; {np.count_nonzero(~unclamped)} disc values clamped")

for kwargs, fragment in (
    ({"width": 7}, "width"),
    ({"width": 0, "filepath": ""}, "filepath"),
    ({"filepath": str(T.TMP / "no_such_dir" / "x.exr")}, "no_such_dir"),
):
    args = {"filepath": str(T.TMP / "bad.exr"), **kwargs}
    try:
        bpy.ops.welkin.export_hdri(**args)
        raise AssertionError(f"export_hdri({kwargs}) did not fail")
    except RuntimeError as error:
        T.check(fragment in str(error), f"{kwargs}: {error}")
        print(f"refused: {str(error).strip()}")
T.check(not (T.TMP / "bad.exr").exists(), "a refused export wrote a file")

T.done("test_addon_export")
