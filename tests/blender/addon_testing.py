# SPDX-License-Identifier: Apache-2.0
"""Shared by the headless Blender tests: install the add-on from its zip the way a user
does, into a temporary scripts directory (the machine's Blender configuration is never
touched), and build small scenes.

Run by scripts/test_blender.sh as
    blender -b --factory-startup --python-use-system-env --python-exit-code 1 --python T
The zip is $WELKIN_ADDON_ZIP when set (scripts/test.sh builds it once), else built here
into the temporary directory by scripts/build_addon.sh.

Blender 4.2 and later (PyPI's bpy 4.2-5.3, through tests/blender/bpy_blender.py) install
the Extension instead, $WELKIN_EXTENSION_ZIP (else scripts/build_extension.sh builds it),
with bpy.ops.extensions.package_install_files as a user installs one from disk. The add-on
package is then bl_ext.user_default.welkin; the tests' `import welkin` / `from
welkin.blender import ...` are pointed at it (an alias kept to these tests).
"""

import atexit
import importlib
import importlib.abc
import importlib.util
import math
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import warnings

import bpy

# A DeprecationWarning raised from Welkin's own modules (the legacy add-on `welkin...`, the
# Extension `bl_ext.<repo>.welkin...`) is an error in the tests: a Blender API the add-on
# uses is going away (e.g. Material.use_nodes, removed in 6.0), and the test shows where.
# tests/blender/bpy_blender.py sets the same filter for the renders it runs.
WELKIN_MODULES = r"(bl_ext\.[^.]+\.)?welkin(\.|$)"
warnings.filterwarnings("error", category=DeprecationWarning, module=WELKIN_MODULES)

ROOT = pathlib.Path(__file__).resolve().parents[2]
TMP = pathlib.Path(tempfile.mkdtemp(prefix="welkin_blender_test_"))
atexit.register(shutil.rmtree, TMP, ignore_errors=True)


def addon_zip():
    path = os.environ.get("WELKIN_ADDON_ZIP")
    if path:
        return pathlib.Path(path)
    subprocess.run(
        ["bash", str(ROOT / "scripts" / "build_addon.sh"), str(TMP / "dist")],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    return next((TMP / "dist").glob("welkin-*.zip"))


EXTENSION = bpy.app.version >= (4, 2, 0)
EXTENSION_PACKAGE = "bl_ext.user_default.welkin"


def is_module_bpy():
    """Blender as a Python module (PyPI's bpy): no Blender binary, no window."""
    return not bpy.app.binary_path


def script_argv():
    """A script's own arguments: those after `--` on Blender's command line, or for the bpy
    module (tests/blender/bpy_blender.py passes them as the script's own) all of them."""
    if "--" in sys.argv:
        return sys.argv[sys.argv.index("--") + 1 :]
    return sys.argv[1:] if is_module_bpy() else []


def blender_command():
    """The command that runs this Blender from the command line: its binary, or for the
    bpy module, tests/blender/bpy_blender.py in the same Python."""
    if is_module_bpy():
        return [sys.executable, str(pathlib.Path(__file__).resolve().parent / "bpy_blender.py")]
    return [bpy.app.binary_path]


def skip(name, reason):
    """A test that cannot run on this Blender: says why and exits successfully."""
    print(f"{name}: SKIPPED on Blender {bpy.app.version_string}: {reason}")
    sys.stdout.flush()
    sys.exit(0)


def extension_zip():
    path = os.environ.get("WELKIN_EXTENSION_ZIP")
    if path:
        return pathlib.Path(path)
    subprocess.run(
        ["bash", str(ROOT / "scripts" / "build_extension.sh"), str(TMP / "dist")],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    return next((TMP / "dist").glob("welkin-*-linux_x64.zip"))


class _AliasFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """`welkin`, `welkin.x` -> the installed extension's bl_ext.user_default.welkin(.x)."""

    def find_spec(self, name, path=None, target=None):
        if name == "welkin" or name.startswith("welkin."):
            return importlib.util.spec_from_loader(name, self)
        return None

    def create_module(self, spec):
        module = importlib.import_module(EXTENSION_PACKAGE + spec.name[len("welkin") :])
        spec.loader_state = module.__spec__
        return module

    def exec_module(self, module):
        # The import system has just set the module's __spec__ to the alias's ("welkin"):
        # put the module's own back, so that its relative imports still agree with
        # __package__ (Python 3.12+ warns "__package__ != __spec__.parent" otherwise).
        module.__spec__ = module.__spec__.loader_state


def user_repo_index():
    """The index of the "user_default" extension repository in the preferences."""
    repos = bpy.context.preferences.extensions.repos
    return next(i for i, r in enumerate(repos) if r.module == "user_default")


def _install_extension():
    prefs = bpy.context.preferences
    prefs.use_preferences_save = False
    result = bpy.ops.extensions.package_install_files(
        filepath=str(extension_zip()), repo="user_default", enable_on_install=True
    )
    check(result == {"FINISHED"}, f"installing the extension: {result}")
    package = importlib.import_module(EXTENSION_PACKAGE)
    sys.modules.pop("welkin", None)
    sys.meta_path.insert(0, _AliasFinder())
    import welkin

    check(welkin is package, f"`welkin` is not the extension: {welkin}")
    module = package.native.module()
    check(module is not None, package.native.message())
    return package, module


def _drop_compiled_module_from_path():
    # The add-on package is called `welkin`, like the compiled module on PYTHONPATH
    # (scripts/test.sh puts build/ there): keep the latter from shadowing the add-on.
    sys.path[:] = [
        p
        for p in sys.path
        if not (os.path.isdir(p) and any(n.startswith("welkin.cpython") for n in os.listdir(p)))
    ]
    sys.modules.pop("welkin", None)


def scripts_dir():
    return TMP / "scripts"


NO_WELKIN_SAYS = "no_welkin: the add-on is not installed"


def command_line_blender(with_addon):
    """(environment, arguments) for a command-line render of this Blender: with the add-on
    as installed here (`--addons welkin`), or as a stock Blender of its own (empty user
    folders, no add-on anywhere; a script first fails the run if Welkin is found, and
    prints NO_WELKIN_SAYS)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if with_addon:
        env["BLENDER_USER_SCRIPTS"] = str(scripts_dir())
        env["BLENDER_USER_CONFIG"] = str(TMP / "config")
        return env, ["--addons", "welkin"]
    home = TMP / "stock"
    for name in ("scripts", "config", "extensions"):
        (home / name).mkdir(parents=True, exist_ok=True)
    env["BLENDER_USER_RESOURCES"] = str(home)
    env["BLENDER_USER_SCRIPTS"] = str(home / "scripts")
    env["BLENDER_USER_CONFIG"] = str(home / "config")
    env["BLENDER_USER_EXTENSIONS"] = str(home / "extensions")
    no_welkin = TMP / "no_welkin.py"
    no_welkin.write_text(
        "import sys, addon_utils\n"
        "loaded = [m for m in sys.modules if m == 'welkin' or m.startswith(('welkin.', 'bl_ext.'))"
        " and m.split('.')[-1] == 'welkin']\n"
        "names = [m.__name__ for m in addon_utils.modules() if m.__name__.split('.')[-1] == 'welkin']\n"
        "assert not loaded and not names, f'Welkin is installed here: {loaded} {names}'\n"
        f"print({NO_WELKIN_SAYS!r})\n"
    )
    return env, ["--python-exit-code", "1", "--python", str(no_welkin)]


def install_addon():
    """Installs and enables the add-on from its zip; returns (add-on package, compiled
    module)."""
    _drop_compiled_module_from_path()
    if EXTENSION:
        return _install_extension()
    prefs = bpy.context.preferences
    prefs.use_preferences_save = False
    (scripts_dir() / "addons").mkdir(parents=True, exist_ok=True)
    filepaths = prefs.filepaths
    if hasattr(filepaths, "script_directories"):  # Blender 3.6+
        filepaths.script_directories.new().directory = str(scripts_dir())
    else:
        filepaths.script_directory = str(scripts_dir())
    bpy.utils.refresh_script_paths()
    bpy.ops.preferences.addon_install(filepath=str(addon_zip()), target="PREFS")
    bpy.ops.preferences.addon_enable(module="welkin")
    import welkin

    assert hasattr(welkin, "bl_info"), f"`welkin` is not the add-on: {welkin}"
    assert pathlib.Path(welkin.__file__).is_relative_to(scripts_dir()), welkin.__file__
    from welkin import native

    module = native.module()
    assert module is not None, native.message()
    return welkin, module


def installed_in_temp(package):
    """Whether the add-on package was installed in the tests' own folders (the machine's
    Blender configuration untouched)."""
    where = pathlib.Path(package.__file__).resolve()
    homes = [scripts_dir()]
    if EXTENSION:
        homes.append(pathlib.Path(bpy.utils.user_resource("EXTENSIONS")))
    return any(where.is_relative_to(h.resolve()) for h in homes) and not str(where).startswith(
        os.path.expanduser("~/.config/blender")
    )


def sun_direction(elevation_deg, azimuth_deg):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))


def aim_sun(obj, elevation_deg, azimuth_deg):
    """Rotates a sun lamp so that its local +Z (towards the sun) points at the given
    elevation and azimuth (counter-clockwise from +X)."""
    from mathutils import Vector

    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = Vector((0, 0, 1)).rotation_difference(
        Vector(sun_direction(elevation_deg, azimuth_deg))
    )


def new_scene(sun_elevation_deg=30.0, sun_azimuth_deg=60.0, resolution="256", camera_z=0.0):
    """An empty scene (the factory objects removed) with one sun lamp and a camera at the
    origin's height camera_z. Returns (scene, sun object)."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    scene = bpy.context.scene
    data = bpy.data.lights.new("Sun", "SUN")
    sun = bpy.data.objects.new("Sun", data)
    scene.collection.objects.link(sun)
    aim_sun(sun, sun_elevation_deg, sun_azimuth_deg)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location = (0.0, 0.0, camera_z)
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.world.welkin.resolution = resolution
    bpy.context.view_layer.update()
    return scene, sun


def world_pixels(image):
    """The Blender image as (H, W, 3), top row first."""
    import numpy as np

    w, h = image.size
    flat = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(flat)
    return flat.reshape(h, w, 4)[::-1, :, :3]


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def done(name):
    print(f"{name}: OK")


def panoramic_camera(scene, width, height, samples=2, compat=None):
    """Makes the scene camera an equirectangular panorama at the origin looking along +X
    with +Z up, so that its image has Blender's Environment Texture mapping (the image
    centre is +X, +Y to the left), and sets up a fast, exact-as-possible Cycles render:
    a tiny pixel filter (samples at the pixel centres), no denoising, linear EXR.
    `compat`: the add-on's compat module (default: the installed add-on's)."""
    import math as m

    cam = scene.camera
    cam.location = (0.0, 0.0, cam.location.z)
    cam.rotation_mode = "XYZ"
    cam.rotation_euler = (m.radians(90.0), 0.0, m.radians(-90.0))
    cam.data.type = "PANO"
    if compat is None:
        from welkin.blender import compat  # the installed add-on's
    compat.camera_panorama(cam.data).panorama_type = "EQUIRECTANGULAR"
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = 0.01
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    compat.set_file_format(scene.render.image_settings, "OPEN_EXR")
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGB"
    scene.view_settings.view_transform = "Standard"


def read_rgb_exr(welkin, path):
    """(H, W, 3) float32, top row first, R G B in that order (read by the core)."""
    import numpy as np

    pixels, names = welkin.read_exr(str(path))
    return np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)


def render_still(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)


class FakeLayout:
    """Records what a panel draws (labels, properties, operators), for headless tests."""

    def __init__(self, log=None):
        self.log = [] if log is None else log
        self.use_property_split = False
        self.active = True

    def _child(self, *args, **kwargs):
        return FakeLayout(self.log)

    row = column = box = _child

    def separator(self, *args, **kwargs):
        pass

    def label(self, text="", **kwargs):
        self.log.append(("label", text))

    def prop(self, data, name, **kwargs):
        getattr(data, name)  # the property must exist
        self.log.append(("prop", name))

    def operator(self, idname, **kwargs):
        self.log.append(("operator", idname))

    def template_list(self, list_type, list_id, data, name, *args, **kwargs):
        getattr(data, name)
        self.log.append(("list", name))


def draw_panel(scene):
    """What Properties > World > Welkin Sky shows for `scene`: a list of (kind, text)."""
    import types

    panel_class = bpy.types.WORLD_PT_welkin_sky
    layout = FakeLayout()
    context = types.SimpleNamespace(world=scene.world, scene=scene)
    T = types.SimpleNamespace(layout=layout)
    panel_class.draw(T, context)
    return layout.log
