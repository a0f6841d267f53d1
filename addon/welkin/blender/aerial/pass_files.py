# SPDX-License-Identifier: GPL-3.0-or-later
"""Write Pass Files: the frame's scene JSON, aerial passes and hazed composite beside each
render, from the render's Z pass (which the compositor's File Output node writes, its path
kept in step with the output path)."""

import json
import os

from ... import native, scene_export
from . import compositor
from . import scene as aerial_scene
from .. import compat
from ..sky.scene_sun import UserError


def _ours(module, path, kind):
    """True when `path` is absent or a file the add-on wrote (so it may be replaced)."""
    if not os.path.exists(path):
        return True
    try:
        if kind == "scene":
            module.SceneDescription.from_json(path)
            return True
        _pixels, names = module.read_exr(path)
    except Exception:
        return False
    if kind == "aerial":
        return sorted(names) in (
            sorted(scene_export.PASS_CHANNELS),
            sorted(scene_export.PASS_CHANNELS + scene_export.CLOUD_CHANNELS),
        )
    return sorted(names) == sorted(scene_export.COMPOSITE_CHANNELS)


def write_frame(scene, frame):
    """Writes the frame's scene JSON, passes and composite; returns their paths."""
    import numpy as np

    module = native.module()
    if module is None:
        raise UserError(native.message())
    # Camera, sun and world first (the likelier faults), as the render's depsgraph had
    # them at this frame (frame_change_post), else as they are now.
    text = at_frame.pop(scene.name, {}).get(frame)
    if text is None or scene.camera is None:
        text = aerial_scene.scene_json(scene, module)
    if isinstance(text, UserError):
        raise text
    base = aerial_scene.base_of(scene)
    paths = {k: scene_export.frame_path(base, k, frame) for k in ("scene", "aerial", "composite")}
    for kind, path in paths.items():
        if not _ours(module, path, kind):
            raise UserError(
                f"{path} exists and was not written by Welkin: not replaced "
                f"(move it, or change Output > Output Path)"
            )
    render_path = scene_export.frame_path(base, "render", frame)
    if not os.path.exists(render_path):
        raise UserError(
            f"the render's depth file {render_path} is missing: the compositor "
            f"must run (Post Processing > Compositing on) with the node "
            f"'{compositor.DEPTH_NODE}'; toggle Aerial Perspective off and on"
        )
    desc = module.SceneDescription.from_json_string(text)
    pixels, names = module.read_exr(render_path)
    depth_name = next((n for n in names if n.startswith("Depth.")), None)
    if depth_name is None:
        raise UserError(
            "the render has no Z pass (View Layer > Passes > Data > Z, linked "
            f"to the '{compositor.DEPTH_NODE}' node): the pass is on from the "
            "next render; toggle Aerial Perspective off and on to relink it"
        )
    if not (pixels[..., names.index(depth_name)] > 0.0).any():
        # An unlinked File Output input writes a constant 0: the Z pass did not arrive.
        raise UserError(
            "the render's Z pass is empty (View Layer > Passes > Data > Z off, "
            "or its link to the 'Welkin Aerial Depth' node removed): it is on "
            "from the next render; toggle Aerial Perspective off and on"
        )
    image = np.stack([pixels[..., names.index(f"Image.{c}")] for c in "RGB"], axis=-1)
    depth = pixels[..., names.index(depth_name)] * np.float32(scene.unit_settings.scale_length)
    depth = np.ascontiguousarray(depth)
    clouds = None
    try:
        inscatter, transmittance = module.aerial_perspective(desc, depth)
        if "clouds" in json.loads(text):
            # Welkin.Clouds marched up to the render's depth (geometry in front hides it).
            passes = module.cloud_passes(desc, depth)
            clouds = np.asarray(passes["Welkin.Clouds"], dtype=np.float32)
            cloud_depth = np.asarray(passes["Welkin.CloudDepth"], dtype=np.float32)
    except (ValueError, OSError) as error:
        raise UserError(str(error)) from None
    layers, channels = [inscatter, transmittance], list(scene_export.PASS_CHANNELS)
    if clouds is not None:
        layers += [clouds, cloud_depth[..., None]]
        channels += list(scene_export.CLOUD_CHANNELS)
    desc.to_json(paths["scene"], overwrite=True)
    module.write_exr(
        paths["aerial"],
        np.concatenate(layers, axis=-1),
        channels,
        overwrite=True,
        attributes=[("welkinScene", text)],
    )
    module.write_exr(
        paths["composite"],
        np.ascontiguousarray(
            scene_export.composite(image, inscatter, transmittance, clouds), dtype=np.float32
        ),
        list(scene_export.COMPOSITE_CHANNELS),
        overwrite=True,
    )
    return paths


# scene name -> {frame: the frame's scene JSON text, or the UserError it raised}
at_frame = {}


def sync_output_path(scene):
    """Points the File Output node at the current output path. A render copies the
    compositor before its first render_pre, so the path is kept in step whenever the
    scene changes, when a file loads and when a render is initialised (render_init, before
    that copy: `blender -b file.blend -o PATH -f N` sets the output path after the file
    loaded, with no update of the scene), not only when a frame's render starts."""
    node = compositor.depth_node(scene)
    if node is not None:
        wanted = scene_export.file_output_base(aerial_scene.base_of(scene))
        if compat.file_output_path(node) != wanted:  # a change recompiles the compositor
            compat.set_file_output_path(node, wanted)
