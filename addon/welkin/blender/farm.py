# SPDX-License-Identifier: GPL-3.0-or-later
"""A frame the add-on could not prepare fails visibly in command-line renders.

`blender -b file.blend -a` (or `-f N`) on a farm: when the sky or the aerial perspective
of a frame cannot be made (a VDB file of the sequence missing, no sun lamp, a file in the
way), rendering that frame with the previous frame's sky, or without its haze, would hand
the farm a wrong picture with exit status 0. Instead the frame fails the way Ctrl-C fails
a background render: fail_frame() prints the reason and raises SIGINT, whose handler is
Blender's own in background mode (creator_signals: "Sent an internal break event"; it
sets G.is_break). Blender then stops the render of that frame without writing it (and
removes its placeholder, Output > Placeholders), renders no later frame, runs the
render_cancel handlers, and exits with EXIT_FAILURE (creator.cc: G.is_break ?
EXIT_FAILURE : EXIT_SUCCESS), in 3.4 as in 4.x and 5.x. The frames before it are on disk.

What a failed render leaves: the frames before the failed one, written by this run, and
nothing for the failed frame or the frames after it that this render was to write (`-a`:
up to the scene's end frame, `-s/-e` included; `-f N`: frame N alone): an image an
earlier run left at one of those frames' paths is removed too (`_remove_frames`), so that
a farm or a script that counts the files on disk never takes an earlier run's frame for
this one. Not removed: movies (one file for all frames), frames kept on purpose
(Output > Overwrite off: Blender skips them), files that are not the render's images
(Write Pass Files' files of an earlier run: each frame's own are replaced when it renders).

Only there: in the interface, and in Python scripts that render from a background session
(bpy.ops.render.render), a failed frame is printed and shown in the panel's status line,
as before (a second break event would kill Blender: "Press ^C again to kill Blender"); and
where Python, not Blender, owns SIGINT (the `bpy` module) nothing is raised either.
"""

import os
import signal
import sys
import time

import bpy

from . import compat

_RENDER_FLAGS = {"-a", "--render-anim", "-f", "--render-frame"}


def command_line_render():
    """True in `blender -b ... -a` / `-f N` (the render Blender was started to do)."""
    if not bpy.app.background:
        return False
    argv = sys.argv
    if "--" in argv:
        argv = argv[: argv.index("--")]  # what follows belongs to Python scripts
    return any(a in _RENDER_FLAGS for a in argv[1:])


def _blender_owns_sigint():
    # None: the handler was not installed from Python (Blender's C handler is).
    return signal.getsignal(signal.SIGINT) is None


def fail_frame(scene, reason, *, remove_written=False):
    """Fails the frame being rendered (command-line renders only; see the module's
    docstring); `remove_written`: the frame's image was already saved (render_post), take
    it away. Returns True when the render was told to stop."""
    frame = scene.frame_current
    if not (command_line_render() and _blender_owns_sigint()):
        return False
    for removed, why in _remove_frames(scene, remove_written):
        print(f"Welkin: removed {removed}: frame {frame} failed ({why})")
    if _state["stopping"]:
        # One break event per process: Blender keeps G.is_break (later frames and `-f`
        # renders are cancelled too), and a second event would kill it at once.
        return True
    _state["stopping"] = True
    print(
        f"Welkin: error: frame {frame} failed: {reason}; the render stops, no file is "
        f"left for frame {frame}, and Blender exits with a non-zero status",
        file=sys.stderr,
    )
    sys.stdout.flush()
    sys.stderr.flush()
    signal.raise_signal(signal.SIGINT)
    return True


# scene name -> time.time() when the frame's render began (render_pre)
_started = {}
# Files older than this process are an earlier run's (the add-on loads before any render).
_PROCESS_START = time.time()
_state = {"stopping": False}


def frame_started(scene):
    """render_pre: a frame's render begins."""
    _started[scene.name] = time.time()


def _single_frame():
    """True for `-f N` (the frames to render are the listed ones, not the scene's range)."""
    argv = sys.argv[: sys.argv.index("--")] if "--" in sys.argv else sys.argv
    return any(a in {"-f", "--render-frame"} for a in argv[1:])


def _remove_frames(scene, remove_written):
    """Deletes what the failed render would have replaced (see the module's docstring):
    the image Blender wrote for the current frame during this render (`remove_written`:
    render_post comes after the file is saved in `-a` and `-f`), and images an earlier run
    left at the paths of the current frame and, for `-a`, the later frames of the range.
    Returns [(path, why)]."""
    render = scene.render
    if compat.is_movie_output(render):  # one file for all frames: never removed
        return []
    frame = scene.frame_current
    started = _started.get(scene.name)
    frames = [frame] if _single_frame() else range(frame, scene.frame_end + 1, max(1, scene.frame_step))
    removed = []
    for f in frames:
        path = render.frame_path(frame=f)
        try:
            if not os.path.isfile(path):
                continue
            mtime = os.path.getmtime(path)
            if mtime < _PROCESS_START - 1.0:
                if not render.use_overwrite:
                    continue  # kept on purpose: Blender skips an existing frame
                why = "an earlier run's frame"
            elif f == frame and remove_written and started is not None and mtime >= started - 2.0:
                why = "written for the failed frame"
            else:
                continue
            os.remove(path)
        except OSError:
            continue
        removed.append((path, why))
    return removed


def _animated(id_):
    """True when `id_` has keyframes, drivers or NLA strips."""
    data = getattr(id_, "animation_data", None) if id_ is not None else None
    return data is not None and (data.action is not None or len(data.drivers) > 0 or len(data.nla_tracks) > 0)


def _moves(ob, with_data):
    """True when the object (or its data, `with_data`), a parent, or a constraint may make
    it change from frame to frame (constraints: their targets may move)."""
    seen = set()
    while ob is not None and ob.name_full not in seen:
        seen.add(ob.name_full)
        if _animated(ob) or len(ob.constraints) > 0 or (with_data and _animated(ob.data)):
            return True
        ob = ob.parent
    return False


def changing_inputs(scene):
    """What the add-on recomputes per frame that may change over the scene's frames: the
    names of the animated camera, sun lamp, world, scene settings and cloud volumes (a
    list, empty for a static scene). A Blender without the add-on renders every frame
    with the saved frame's sky, lamp and haze, right only when this is empty
    (docs/pipelines.md#saved-files-without-the-add-on). Conservative: any keyframe,
    driver, NLA strip or constraint on them counts."""
    from .clouds import scene as cloud_scene
    from .sky import scene_sun

    changing = []
    if _animated(scene) or any(m.camera is not None for m in scene.timeline_markers):
        changing.append(f"scene '{scene.name}'")
    if scene.camera is not None and _moves(scene.camera, with_data=True):
        changing.append(f"camera '{scene.camera.name}'")
    world = scene.world
    if world is not None:
        if _animated(world) or _animated(world.node_tree):
            changing.append(f"world '{world.name}'")
        try:
            lamp, _warning = scene_sun.choose_sun(scene, world.welkin)
        except scene_sun.UserError:
            lamp = None
        if lamp is not None and _moves(lamp, with_data=False):
            changing.append(f"sun lamp '{lamp.name}'")
    for ob in cloud_scene.marked_volumes(scene):
        if ob.data.is_sequence or _moves(ob, with_data=True):
            changing.append(f"cloud volume '{ob.name}'")
    return changing


# --- files a Blender without the add-on must not render ----------------------------------
# A scene whose sky or haze changes over its frames, saved without a current farm bake,
# renders wrong in a Blender without Welkin (every frame with the saved frame's sky, lamp
# and haze; or a stale bake), with exit status 0: nothing in a .blend runs there when
# Python scripts are off, and a missing image renders magenta without an error. What
# such a Blender does refuse is a scene without a camera: "Cannot render, no camera",
# nothing written, exit status 1 (-a and -f). So the file is saved with the scene's
# camera kept in a custom property (CAMERA_KEPT) and Scene.camera empty; the add-on puts
# the camera back as soon as it sees the file (after saving, when a file loads, and when
# it is enabled after the file was loaded: `blender -b f.blend --addons welkin -a`).
# Not covered: a scene whose timeline markers bind cameras (Blender picks the camera from
# the markers at render time), and scenes linked from libraries.

CAMERA_KEPT = "welkin_camera_for_the_add_on"


def hide_camera(scene):
    """Empties Scene.camera for the saved file (see above); False when it cannot work."""
    if scene.library is not None or scene.camera is None or CAMERA_KEPT in scene:
        return False
    if any(m.camera is not None for m in scene.timeline_markers):
        return False
    scene[CAMERA_KEPT] = scene.camera
    scene.camera = None
    return True


def restore_cameras():
    """Puts back every camera hide_camera kept (save_post, load_post, registration)."""
    for scene in bpy.data.scenes:
        if scene.library is not None or CAMERA_KEPT not in scene:
            continue
        camera = scene[CAMERA_KEPT]
        del scene[CAMERA_KEPT]
        if scene.camera is None and isinstance(camera, bpy.types.Object):
            scene.camera = camera
