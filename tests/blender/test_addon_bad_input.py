# SPDX-License-Identifier: Apache-2.0
"""Bad input: the compiled module missing or built for another Python, no sun lamp,
several sun lamps, the sun below the horizon, the camera below the ground. Each ends in a
clear message (an operator report, which bpy.ops raises as RuntimeError in scripts; a
warning where the sky can still be made), never a traceback from the add-on, and no user
data is lost."""

import importlib
import math
import os
import pathlib
import re
import sys
import zipfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import addon_utils  # noqa: E402
import bpy  # noqa: E402
import numpy as np  # noqa: E402


def expect_error(operator, fragment, **kwargs):
    try:
        operator(**kwargs)
    except RuntimeError as error:
        T.check(fragment in str(error), f"error {str(error)!r} does not mention {fragment!r}")
        T.check("Traceback" not in str(error), f"a traceback in the report: {error}")
        print(f"reported: {str(error).strip()}")
        return
    raise AssertionError(f"{operator} did not fail (expected {fragment!r})")


def broken_zip(name, rename_module_to=None):
    """The add-on zip without its module, or with the module under another Python's name."""
    good = T.addon_zip()
    path = T.TMP / name
    with zipfile.ZipFile(good) as src, zipfile.ZipFile(path, "w") as dst:
        for item in src.infolist():
            if "/_native/" in item.filename:
                if rename_module_to is None:
                    continue
                dst.writestr(f"welkin/_native/{rename_module_to}", src.read(item))
            else:
                dst.writestr(item, src.read(item))
    return path


def broken_extension(name, python_tag=None):
    """The Extension zip without its wheels (python_tag None), or with only one wheel,
    relabelled as built for another Python (its file name, tags and manifest entry)."""
    good = T.extension_zip()
    path = T.TMP / name
    with zipfile.ZipFile(good) as src, zipfile.ZipFile(path, "w") as dst:
        wheels = [i.filename for i in src.infolist() if i.filename.endswith(".whl")]
        T.check(len(wheels) == 2, f"the Extension carries {wheels}, not a cp311 and a cp313 wheel")
        renamed = None
        if python_tag is not None:
            renamed = re.sub(r"cp3\d+-cp3\d+", f"{python_tag}-{python_tag}", wheels[0])
        for item in src.infolist():
            data = src.read(item)
            if item.filename in wheels:
                if item.filename == wheels[0] and renamed is not None:
                    dst.writestr(renamed, data)
            elif item.filename.endswith("blender_manifest.toml"):
                lines = data.decode().splitlines(keepends=True)
                if renamed is None:
                    lines = [line for line in lines if not line.startswith("wheels")]
                else:
                    lines = [
                        f'wheels = ["./wheels/{pathlib.PurePosixPath(renamed).name}"]\n'
                        if line.startswith("wheels")
                        else line
                        for line in lines
                    ]
                dst.writestr(item, "".join(lines))
            else:
                dst.writestr(item, data)
    return path


def install(zip_path):
    bpy.ops.preferences.addon_install(filepath=str(zip_path), target="PREFS", overwrite=True)
    bpy.ops.preferences.addon_enable(module="welkin")


def uninstall():
    bpy.ops.preferences.addon_disable(module="welkin")
    for name in [n for n in sys.modules if n == "welkin" or n.startswith("welkin.")]:
        del sys.modules[name]


def check_registered_without_module(label, fragment, hint):
    T.check(hasattr(bpy.types, "WORLD_PT_welkin_sky"), f"{label}: no panel registered")
    native = importlib.import_module(package + ".native")
    T.check(
        native.module() is None and fragment in native.message(),
        f"{label}: message {native.message()!r} lacks {fragment!r}",
    )
    T.check(
        hint in native.message() and "Python 3.11" in native.message() and "3.13" in native.message(),
        f"{label}: the message does not say which Blender, Python and file to use",
    )
    scene, _sun = T.new_scene()
    shown = T.draw_panel(scene)
    shown_text = " ".join(text for kind, text in shown if kind == "label")
    T.check(
        fragment in shown_text and hint in shown_text,
        f"{label}: the panel does not show the message: {shown}",
    )
    T.check(not any(kind == "operator" for kind, _ in shown), "operators offered without module")
    nodes_before = len(scene.world.node_tree.nodes)
    expect_error(bpy.ops.welkin.update_sky, fragment)
    T.check(len(scene.world.node_tree.nodes) == nodes_before, "world changed without module")


# --- the module missing, then built for another Python: the add-on registers, says why.
T._drop_compiled_module_from_path()
prefs = bpy.context.preferences
prefs.use_preferences_save = False
if not T.EXTENSION:
    package = "welkin"
    (T.scripts_dir() / "addons").mkdir(parents=True, exist_ok=True)
    prefs.filepaths.script_directory = str(T.scripts_dir())
    bpy.utils.refresh_script_paths()
    for zip_name, rename, fragment in (
        ("no_module.zip", None, "compiled module is missing"),
        ("other_python.zip", "welkin.cpython-310-x86_64-linux-gnu.so", "built for another Python"),
    ):
        install(broken_zip(zip_name, rename))
        T.check(addon_utils.check("welkin")[1], f"{zip_name}: the add-on did not register")
        check_registered_without_module(zip_name, fragment, "build_addon.sh")
        uninstall()
else:
    # Blender 4.2+: the Extension without its wheel registers and says why; one whose
    # wheel is for another Python is refused by Blender's installer, naming the versions.
    package = T.EXTENSION_PACKAGE
    result = bpy.ops.extensions.package_install_files(
        filepath=str(broken_extension("no_wheel.zip")), repo="user_default", enable_on_install=True
    )
    T.check(result == {"FINISHED"}, f"the Extension without its wheel: {result}")
    T.check(addon_utils.check(package)[1], "the Extension without its wheel did not register")
    check_registered_without_module("no wheel", "compiled module is missing", "build_extension.sh")
    bpy.ops.extensions.package_uninstall(repo_index=T.user_repo_index(), pkg_id="welkin")
    for name in [n for n in sys.modules if n == package or n.startswith(package + ".")]:
        del sys.modules[name]
    try:
        result = bpy.ops.extensions.package_install_files(
            filepath=str(broken_extension("cp310.zip", "cp310")), repo="user_default", enable_on_install=True
        )
        refusal = None if result == {"FINISHED"} else str(result)
    except RuntimeError as error:
        refusal = str(error)
    T.check(
        refusal is not None and "Python" in refusal and "3.10" in refusal,
        f"a wheel for Python 3.10 was not refused with a message: {refusal!r}",
    )
    T.check(not addon_utils.check(package)[1], "the cp310 Extension was enabled")
    print(f"refused by Blender: {refusal.strip()}")

# --- the real add-on.
addon, welkin = T.install_addon()
atm = welkin.Atmosphere.preset(welkin.Atmosphere.preset_names()[0])  # the add-on's default

# No sun lamp: refused, nothing changed (no nodes, no images, no world created).
scene, sun = T.new_scene()
bpy.data.objects.remove(sun)
nodes_before = [n.name for n in scene.world.node_tree.nodes]
images_before = set(bpy.data.images.keys())
expect_error(bpy.ops.welkin.update_sky, "no sun lamp")
T.check([n.name for n in scene.world.node_tree.nodes] == nodes_before, "nodes changed")
T.check(set(bpy.data.images.keys()) == images_before, "images created")
world = scene.world
scene.world = None
expect_error(bpy.ops.welkin.update_sky, "no sun lamp")
T.check(scene.world is None and "Welkin World" not in bpy.data.worlds, "a world was created")
scene.world = world
expect_error(bpy.ops.welkin.remove_sky, "no Welkin sky")

# Several sun lamps: the first by name, with a warning; a chosen one without.
scene, sun_b = T.new_scene(30.0, 0.0)
sun_b.name = "B sun"
data = bpy.data.lights.new("A sun", "SUN")
sun_a = bpy.data.objects.new("A sun", data)
scene.collection.objects.link(sun_a)
T.aim_sun(sun_a, 60.0, 90.0)
bpy.context.view_layer.update()
bpy.ops.welkin.update_sky()
settings = scene.world.welkin
T.check(
    "2 sun lamps" in settings.warnings and "'A sun'" in settings.warnings,
    f"no several-lamps warning: {settings.warnings!r}",
)
expected = welkin.sun(atm, 0.0, T.sun_direction(60.0, 90.0)).direct_irradiance_rgb
T.check(math.isclose(sun_a.data.energy, max(expected), rel_tol=1e-5), "not the first lamp")
settings.sun_object = sun_b
bpy.ops.welkin.update_sky()
T.check(settings.warnings == "", f"a warning with a chosen lamp: {settings.warnings!r}")
expected = welkin.sun(atm, 0.0, T.sun_direction(30.0, 0.0)).direct_irradiance_rgb
T.check(math.isclose(sun_b.data.energy, max(expected), rel_tol=1e-5), "not the chosen lamp")
print("several sun lamps: first by name with a warning, or the chosen one")

# The sun below the horizon: twilight sky, lamp at strength 0, a warning.
scene, sun = T.new_scene(-4.0, 30.0)
bpy.ops.welkin.update_sky()
settings = scene.world.welkin
T.check("below the horizon" in settings.warnings, f"no warning: {settings.warnings!r}")
T.check(sun.data.energy == 0.0, f"lamp strength {sun.data.energy} with the sun set")
sky = T.world_pixels(settings.sky_image)
T.check(np.all(np.isfinite(sky)) and sky[0].mean() > 0.0, "twilight sky not finite and positive")
print("sun below the horizon: twilight sky, lamp off, warning")

# The camera below the ground: the sky of an observer on the ground, and a warning.
scene, sun = T.new_scene(30.0, 30.0, camera_z=-50.0)
bpy.ops.welkin.update_sky()
settings = scene.world.welkin
T.check("below the ground" in settings.warnings, f"no warning: {settings.warnings!r}")
sky = T.world_pixels(settings.sky_image)
dirs = welkin.equirect_pixel_directions(256, 128)
ref = welkin.sky_radiance(atm, 0.0, T.sun_direction(30.0, 30.0), dirs[0, :1], output="rgb")[0]
T.check(np.allclose(sky[0, 0], ref, rtol=0.02), "camera below the ground: not the ground sky")
# A camera above the ground raises the observer.
scene.camera.location.z = 3000.0
bpy.context.view_layer.update()
bpy.ops.welkin.update_sky()
T.check(settings.warnings == "", settings.warnings)
ref = welkin.sky_radiance(atm, 3000.0, T.sun_direction(30.0, 30.0), dirs[0, :1], output="rgb")[0]
T.check(
    np.allclose(T.world_pixels(settings.sky_image)[0, 0], ref, rtol=0.02),
    "camera height not added to the observer altitude",
)
print("camera below the ground: ground sky with a warning; camera height is used")

# A handler hitting bad input (the lamp deleted under an animated, live sky) logs, no raise.
bpy.data.objects.remove(sun)
scene.frame_set(2)
T.check("no sun lamp" in settings.status, f"handler status: {settings.status!r}")
print("handler with no sun lamp: logged, no exception")

# An unsupported Blender (older than 3.4): register() prints one line saying which Blender
# Welkin needs and registers nothing (no traceback). bpy.app is swapped for the call.
import contextlib  # noqa: E402
import io  # noqa: E402
import types  # noqa: E402

real_app = bpy.app
printed = io.StringIO()
addon.unregister()
T.check(not hasattr(bpy.types, "WORLD_PT_welkin_sky"), "unregister left the panel")
try:
    bpy.app = types.SimpleNamespace(version=(3, 3, 0), version_string="3.3.0")
    with contextlib.redirect_stdout(printed):
        addon.register()
finally:
    bpy.app = real_app
lines = printed.getvalue().strip().splitlines()
T.check(
    len(lines) == 1 and "3.3.0" in lines[0] and "3.4" in lines[0] and "not supported" in lines[0],
    f"unsupported Blender: printed {lines!r}",
)
T.check(not hasattr(bpy.types, "WORLD_PT_welkin_sky"), "registered on an unsupported Blender")
print(f"unsupported Blender: {lines[0]}")
addon.register()
T.check(hasattr(bpy.types, "WORLD_PT_welkin_sky"), "the add-on did not register again")

T.done("test_addon_bad_input")
