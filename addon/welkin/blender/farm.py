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
        argv = argv[:argv.index("--")]  # what follows belongs to Python scripts
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
    if remove_written:
        removed = _remove_written_frame(scene)
        if removed:
            print(f"Welkin: removed {removed}: frame {frame} failed")
    if _state["stopping"]:
        # One break event per process: Blender keeps G.is_break (later frames and `-f`
        # renders are cancelled too), and a second event would kill it at once.
        return True
    _state["stopping"] = True
    print(f"Welkin: error: frame {frame} failed: {reason}; the render stops, no file is "
          f"left for frame {frame}, and Blender exits with a non-zero status", file=sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    signal.raise_signal(signal.SIGINT)
    return True


# scene name -> time.time() when the frame's render began (render_pre)
_started = {}
_state = {"stopping": False}


def frame_started(scene):
    """render_pre: a frame's render begins."""
    _started[scene.name] = time.time()


def _remove_written_frame(scene):
    """Deletes the image file Blender wrote for the current frame during this render
    (render_post comes after the file is saved in `-a` and `-f`), so that a failed frame
    leaves no file. Movies and files older than the frame's render are left alone.
    Returns the removed path or None."""
    render = scene.render
    if compat.is_movie_output(render):  # one file for all frames: never removed
        return None
    path = render.frame_path(frame=scene.frame_current)
    started = _started.get(scene.name)
    try:
        if started is None or os.path.getmtime(path) < started - 2.0:
            return None
        os.remove(path)
    except OSError:
        return None
    return path
