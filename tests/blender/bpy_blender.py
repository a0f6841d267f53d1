# SPDX-License-Identifier: Apache-2.0
"""The `blender` command line, for Blender as a Python module (PyPI's `bpy`, 4.2-5.3).

scripts/test_blender.sh runs each headless test under a bpy venv as
    build/venv-bpy-<version>/bin/python tests/blender/bpy_blender.py -b --factory-startup \
        --python-use-system-env --python-exit-code 1 --python T
and the tests' own `blender -b scene.blend --addons welkin -E WELKIN -o ... -f 1` calls go
through addon_testing.blender_command(), which names this script there. The arguments are
taken in order as Blender takes them: a .blend file opens, -E/-o/-F/-x/-s/-e/-j set the
scene, -f renders frames (each as a one-frame animation, as Blender does), -a the animation, --addons enables add-ons (a name
that is not a legacy add-on is looked up among the installed extensions, bl_ext.<repo>.),
--python runs a script (its exceptions exit with --python-exit-code). Enough for the
project's tests, not a full emulation: unknown options fail loudly.

The user folders (scripts, config, extensions) are a temporary directory unless the
environment names them, so the machine's Blender settings are never touched; it is removed
at exit, with whatever the script registered with atexit (the tests' own temporary folders)
and Blender's session temporary folder.
"""

import atexit
import os
import pathlib
import runpy
import shutil
import sys
import tempfile
import traceback
import warnings

if "BLENDER_USER_RESOURCES" not in os.environ:
    _home = tempfile.mkdtemp(prefix="welkin_bpy_home_")
    atexit.register(shutil.rmtree, _home, ignore_errors=True)
    os.environ["BLENDER_USER_RESOURCES"] = _home
    os.environ.setdefault("BLENDER_USER_CONFIG", os.path.join(_home, "config"))
    os.environ.setdefault("BLENDER_USER_EXTENSIONS", os.path.join(_home, "extensions"))

import bpy  # noqa: E402

# As in addon_testing.py: a DeprecationWarning from Welkin's own modules is an error, here
# for the renders and add-on runs the tests start through this script.
warnings.filterwarnings("error", category=DeprecationWarning, module=r"(bl_ext\.[^.]+\.)?welkin(\.|$)")

FLAGS = {
    "-b",
    "--background",
    "--factory-startup",
    "--python-use-system-env",
    "--disable-autoexec",
    "-noaudio",
}


def enable_addon(name):
    import addon_utils

    candidates = [name]
    if not any(m.__name__ == name for m in addon_utils.modules()):
        candidates = [
            m.__name__
            for m in addon_utils.modules()
            if m.__name__.startswith("bl_ext.") and m.__name__.split(".")[-1] == name
        ]
    if not candidates:
        raise SystemExit(f"bpy_blender: add-on {name!r} is not installed")
    module = addon_utils.enable(candidates[0], default_set=True, handle_error=None)
    if module is None:
        raise SystemExit(f"bpy_blender: add-on {candidates[0]!r} could not be enabled")


def render_init():
    """The binary's `-a` and `-f` run the render_init handlers before the render pipeline
    checks the scene (RE_RenderAnim: "call hooks before taking a copy of scene->r"), so a
    handler can still set up the scene (the add-on gives a saved file its camera back,
    blender/farm.py); the render operator checks first. Here they run before the operator,
    as the binary runs them, and the operator runs them again (the add-on's are
    idempotent)."""
    scene = bpy.context.scene
    for handler in list(bpy.app.handlers.render_init):
        handler(scene, None)


def render_frames(frames):
    """-f: Blender renders each frame as an animation of that one frame (RE_RenderAnim from
    the frame to itself): the output path's #### becomes the frame and the animation
    handlers run. Here the scene's frame range is set to the frame for the render and put
    back after it."""
    scene = bpy.context.scene
    start, end = scene.frame_start, scene.frame_end
    try:
        for frame in frames:
            scene.frame_start = scene.frame_end = frame
            render_init()
            bpy.ops.render.render(animation=True)
    finally:
        scene.frame_start, scene.frame_end = start, end


def frame_list(text):
    frames = []
    for part in text.split(","):
        a, _, b = part.partition("..")
        frames += list(range(int(a), int(b) + 1)) if b else [int(a)]
    return frames


def finish(code):
    """Exits with `code` at once, as Blender does after --python-exit-code, but first runs
    the atexit functions (the tests' and this script's clean-ups) and removes Blender's
    session temporary folder, which os._exit alone would leave (Blender removes it when
    the interpreter finalizes).

    The result is settled before the interpreter would finalize, and it never does: bpy
    4.2.23 itself crashes (SIGSEGV) while Python finalizes after any script that registered
    a property with update= or a handler, whoever's they are (a plain `python -c` doing so
    exits 139 there). Through os._exit a 4.2 run is judged by the tests' own results, as
    on every other version, never by that crash at exit."""
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        atexit._run_exitfuncs()
        session = bpy.app.tempdir  # Blender's session folder (blender_XXXXXX/), not its parent
        if os.path.basename(os.path.dirname(session)).startswith("blender_"):
            shutil.rmtree(session, ignore_errors=True)
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def main(argv):
    exit_code = 0
    i = 0
    if "--factory-startup" in argv:
        bpy.ops.wm.read_factory_settings(use_empty=False)
        bpy.context.preferences.use_preferences_save = False
    while i < len(argv):
        arg = argv[i]
        value = argv[i + 1] if i + 1 < len(argv) else None
        scene = bpy.context.scene
        if arg in FLAGS:
            i += 1
            continue
        if arg == "--":
            break
        i += 2
        if arg == "--python-exit-code":
            exit_code = int(value)
        elif arg in ("-P", "--python"):
            sys.argv = [value] + argv[argv.index("--") + 1 :] if "--" in argv else [value]
            try:
                runpy.run_path(value, run_name="__main__")
            except SystemExit as stop:
                if stop.code not in (None, 0):
                    raise
            except BaseException:
                traceback.print_exc()
                if exit_code:
                    finish(exit_code)
        elif arg == "--addons":
            for name in value.split(","):
                enable_addon(name)
        elif arg in ("-E", "--engine"):
            scene.render.engine = value
        elif arg in ("-o", "--render-output"):
            scene.render.filepath = value
        elif arg in ("-F", "--render-format"):
            settings = scene.render.image_settings
            if hasattr(settings, "media_type"):  # 5.0: the media type first, as -F does
                settings.media_type = {"OPEN_EXR_MULTILAYER": "MULTI_LAYER_IMAGE", "FFMPEG": "VIDEO"}.get(
                    value, "IMAGE"
                )
            settings.file_format = value
        elif arg in ("-x", "--use-extension"):
            scene.render.use_file_extension = bool(int(value))
        elif arg in ("-s", "--frame-start"):
            scene.frame_start = int(value)
        elif arg in ("-e", "--frame-end"):
            scene.frame_end = int(value)
        elif arg in ("-j", "--frame-jump"):
            scene.frame_step = int(value)
        elif arg in ("-f", "--render-frame"):
            render_frames(frame_list(value))
        elif arg in ("-a", "--render-anim"):
            i -= 1
            render_init()
            bpy.ops.render.render(animation=True)
        elif arg.endswith(".blend") and pathlib.Path(arg).is_file():
            i -= 1
            bpy.ops.wm.open_mainfile(filepath=arg)
        else:
            raise SystemExit(f"bpy_blender: unsupported argument {arg!r}")


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except SystemExit as stop:
        if stop.code not in (None, 0):
            print(stop.code if isinstance(stop.code, str) else "", file=sys.stderr)
            finish(stop.code if isinstance(stop.code, int) else 1)
    finish(0)
