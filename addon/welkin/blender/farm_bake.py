# SPDX-License-Identifier: GPL-3.0-or-later
"""Bake for Farm: everything an animated Welkin scene needs per frame, in the file and
beside it, so that a Blender without the add-on (a farm's stock Blender, Python scripts
off) renders every frame of the range as the add-on does (docs/pipelines.md#bake-for-farm).

For each frame of the scene's range the add-on's own per-frame work runs (scene.frame_set:
the sky, the lamp, the aerial table), then what it produced is kept:
  * the images its nodes read (the world's sky, the aerial tables) as one OpenEXR file per
    frame, written by Blender's own writer (full float, lossless) to
    //welkin_farm/<scene>/<image>_NNNN.exr beside the .blend (relative paths), and new
    image data-blocks of source SEQUENCE that read them; the add-on's texture nodes are
    pointed at those, with image users that map frame F to file F - start + 1. Blender
    cannot pack an image sequence into a .blend, and one packed image per frame would need
    as many texture nodes as frames in every shader; so the folder travels with the file.
  * the values of the add-on's nodes (world and aerial group) and of the synced sun lamp
    (colour, strength, angle) that change over the range, keyed per frame with constant
    interpolation on the node trees' and the lamp's animation.
Nothing is changed in the file until every frame is baked; a cancelled bake (ESC, or an
error) removes the files it wrote and leaves the scene as it was (without a bake).
The user's nodes are never touched: only the add-on's (world_nodes.ROLE_KEY, the aerial
group) are re-pointed and keyed.

A stale bake: each frame's key (farm_bake.frame_key: the frame's sky key and scene JSON) is
stored. With the add-on, a frame whose key differs from the stored one (the scene was
edited after baking) is refused: a command-line render fails (farm.fail_frame), other
renders and saving say so in the status line. Update Sky, or aerial perspective turned on
or off, drops the bake (the live nodes come back). A stock Blender cannot check the key:
a stale bake renders as baked there; saving says so when the bake is stale.
"""

import os

import bpy
import numpy as np

from .. import farm_bake as plan, native
from . import compat, farm
from .aerial import frame as aerial_frame, scene as aerial_scene
from .sky import scene_sun, update
from .sky.scene_sun import UserError

RECORD = "welkin_farm_bake"  # scene custom property: the bake's record (JSON)
MARK = "welkin_farm"  # on the sequence images: the scene they belong to
_SCREEN_KIND = "group"
_WORLD_KIND = "world"
LAMP_PROPS = ("color", "energy", "angle")


def record(scene):
    return plan.decode(scene.get(RECORD, ""))


def frame_key(scene, depsgraph=None):
    """The current frame's key (farm_bake.frame_key) as the add-on computes it for a render
    of this frame, from `depsgraph` (the render's own) or the scene as it is."""
    module = native.module()
    if module is None:
        raise UserError(native.message())
    world = scene.world
    if world is None or not world.welkin.active:
        raise UserError("no Welkin sky in the scene's world: press Update Sky first")
    settings = world.welkin
    request, _lamp, _warnings = scene_sun.request_for(scene, settings, depsgraph)
    clouds = update.clouds_of(scene, depsgraph)
    sky_key = update.sky_key(settings, request, clouds)
    text = aerial_scene.scene_json(scene, module, depsgraph) if scene.welkin_aerial.enabled else ""
    # Cycles' pixel filter sets the screen table's margins (aerial_frame.screen_request).
    cycles = getattr(scene, "cycles", None)
    engine = f"{scene.render.engine}/{getattr(cycles, 'filter_width', '')!r}"
    return plan.frame_key(sky_key, text, engine)


def check_frame(scene, depsgraph=None):
    """None when the scene has no bake; "" when the current frame's bake is current; else
    why it cannot be rendered (a stale or missing frame)."""
    rec = record(scene)
    if rec is None:
        return None
    frame = scene.frame_current
    stored = rec["frames"].get(str(frame))
    if stored is None:
        return (
            f"frame {frame} is outside the baked range {rec['start']}-{rec['end']}: press Bake for Farm again"
        )
    try:
        key = frame_key(scene, depsgraph)
    except UserError as error:
        return f"frame {frame}: {error}"
    if key != stored:
        return (
            f"the farm bake of frame {frame} is stale (the camera, sun, sky or render settings "
            f"changed after Bake for Farm): press Bake for Farm again"
        )
    return ""


def on_frame(scene, depsgraph, log):
    """For the frame_change_post handlers: True when a bake handles this frame (the
    add-on's own update must not run: the baked images and keys render it). A stale frame
    is refused: a command-line render fails (farm.fail_frame), else `log` says it."""
    problem = check_frame(scene, depsgraph)
    if problem is None:
        return False
    if problem and not _state["verifying"]:
        reason = f"Bake for Farm: {problem}"
        if not (depsgraph is not None and depsgraph.mode == "RENDER" and farm.fail_frame(scene, reason)):
            log(reason)
    return True


def verify(scene):
    """The baked frames whose key is stale now (every frame evaluated; the current frame is
    put back). Raises UserError when a key cannot be computed."""
    rec = record(scene)
    if rec is None:
        return []
    current = scene.frame_current
    keys = {}
    _state["verifying"] = True
    try:
        for f in plan.frames_of(rec["start"], rec["end"]):
            scene.frame_set(f)
            keys[f] = frame_key(scene, bpy.context.evaluated_depsgraph_get())
    finally:
        _state["verifying"] = False
        scene.frame_set(current)
    return plan.stale_frames(rec["frames"], keys)


_state = {"verifying": False}  # verify() evaluates the frames: the handlers say nothing


# --- what the bake keeps -----------------------------------------------------------------


def _trees(scene):
    """(kind, name, tree, nodes) of the add-on's node trees the bake covers."""
    out = []
    world = scene.world
    if world is not None and world.node_tree is not None:
        ours = [n for n in world.node_tree.nodes if n.get(update.world_nodes.ROLE_KEY)]
        out.append((_WORLD_KIND, world.name, world.node_tree, ours))
    if scene.welkin_aerial.enabled:
        group = bpy.data.node_groups.get(aerial_frame.SHADER_GROUP)
        if group is not None and group.get(aerial_frame.MARK):
            out.append((_SCREEN_KIND, group.name, group, list(group.nodes)))
    return out


def _tree(kind, name):
    if kind == _WORLD_KIND:
        world = bpy.data.worlds.get(name)
        return world.node_tree if world is not None else None
    return bpy.data.node_groups.get(name)


def _value(socket):
    v = socket.default_value
    try:
        return tuple(float(x) for x in v)
    except TypeError:
        return float(v)


def _snapshot(scene, lamp):
    """The frame's state: {name: value} of the add-on's unlinked node inputs and the synced
    lamp's values, the structure (links, images) that must not change over the range."""
    values, structure = {}, []
    for kind, name, tree, nodes in _trees(scene):
        for node in nodes:
            for i, socket in enumerate(node.inputs):
                if socket.is_linked or not hasattr(socket, "default_value"):
                    continue
                if isinstance(socket.default_value, (str, bpy.types.ID)) or socket.default_value is None:
                    continue
                values[f"{kind}\t{name}\t{node.name}\t{i}"] = _value(socket)
            image = getattr(node, "image", None)
            if image is not None:
                structure.append((kind, name, node.name, image.name))
        structure += sorted(
            (
                kind,
                name,
                link.from_node.name,
                link.from_socket.identifier,
                link.to_node.name,
                link.to_socket.identifier,
            )
            for link in tree.links
            if link.to_node in nodes
        )
    if lamp is not None:
        for prop in LAMP_PROPS:
            if hasattr(lamp.data, prop):
                values[f"lamp\t{lamp.name}\t\t{prop}"] = _value_of(getattr(lamp.data, prop))
    return values, structure


def _value_of(v):
    try:
        return tuple(float(x) for x in v)
    except TypeError:
        return float(v)


def _images(structure):
    """(kind, tree name, node name, image name) of the texture nodes in the bake's trees."""
    return [s for s in structure if len(s) == 4]


def _refuse(scene):
    """Why the scene cannot be baked (UserError), before anything is changed."""
    if not bpy.data.filepath:
        raise UserError(
            f"save the .blend first: the bake's images are written beside it (//{plan.FOLDER}/<scene>/)"
        )
    world = scene.world
    if world is None or not world.welkin.active:
        raise UserError("no Welkin sky in the scene's world: press Update Sky first")
    update.refuse_if_not_editable(world)
    if world.welkin_place_time.enabled:
        raise UserError(
            "Place and Time aims the lamps itself on every frame, which Bake for Farm does not "
            "keep yet: render this scene with the add-on (docs/pipelines.md#bake-for-farm)"
        )
    if world.welkin_clouds.ground_shadows:
        raise UserError(
            "Ground Shadows are made per frame by the add-on, which Bake for Farm does not keep "
            "yet: render this scene with the add-on (docs/pipelines.md#bake-for-farm)"
        )
    for other in bpy.data.scenes:
        if other != scene and record(other) is not None:
            raise UserError(f"scene '{other.name}' holds a farm bake already (one baked scene per file)")
    lamp = _sync_lamp(scene)
    if (
        lamp is not None
        and lamp.data.animation_data is not None
        and lamp.data.animation_data.action is not None
    ):
        raise UserError(
            f"the sun lamp's data '{lamp.data.name}' is animated, and Sync Lamp sets its colour "
            f"and strength on every frame: remove its keyframes, or turn Sync Lamp off"
        )


def _sync_lamp(scene):
    settings = scene.world.welkin
    if not settings.sync_lamp:
        return None
    lamp, _warning = scene_sun.choose_sun(scene, settings)
    return lamp


class Bake:
    """One bake, a frame per step() (the modal operator runs one per timer event; execute()
    all at once). Nothing in the file changes before finish()."""

    def __init__(self, scene):
        self.scene = scene
        _refuse(scene)
        self.frames = plan.frames_of(scene.frame_start, scene.frame_end)
        self.current = scene.frame_current
        self.written = []
        self.keys = {}
        self.values = []
        self.structure = None
        self.lamp = None
        self.index = 0
        drop(scene)  # a new bake replaces the old: the live nodes first

    def __len__(self):
        return len(self.frames)

    def step(self):
        """Bakes the next frame; True when every frame is baked (then call finish())."""
        scene = self.scene
        f = self.frames[self.index]
        scene.frame_set(f)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        _check_updated(scene, depsgraph, f)
        self.lamp = _sync_lamp(scene)
        values, structure = _snapshot(scene, self.lamp)
        if self.structure is None:
            self.structure = structure
        elif structure != self.structure:
            raise UserError(
                f"frame {f}: the add-on's nodes change shape over the range (e.g. the sun disc "
                f"shown on some frames only), which keyframes cannot hold"
            )
        self.values.append(values)
        self.keys[f] = frame_key(scene, depsgraph)
        for image_name in sorted({s[3] for s in _images(structure)}):  # once each (EEVEE: 16 nodes, 1 image)
            path = self._path(image_name, self.index + 1)
            _write_exr(bpy.data.images[image_name], path)
            self.written.append(path)
        self.index += 1
        return self.index == len(self.frames)

    def _path(self, image_name, index):
        rel = plan.sequence_path(self.scene.name, image_name, index)
        return bpy.path.abspath(rel)

    def cancel(self):
        for path in self.written:
            try:
                os.remove(path)
            except OSError:
                pass
        self.scene.frame_set(self.current)

    def finish(self):
        """Points the add-on's texture nodes at the sequences, keys the changing values,
        stores the record; puts the current frame back."""
        scene = self.scene
        start, end = self.frames[0], self.frames[-1]
        images = []
        farm_images = {}
        for kind, tree_name, node_name, image_name in _images(self.structure):
            live = bpy.data.images[image_name]
            if image_name not in farm_images:
                path = plan.sequence_path(scene.name, image_name, 1)
                farm_images[image_name] = _sequence_image(scene, live, path)
            farm_image = farm_images[image_name]
            node = _tree(kind, tree_name).nodes[node_name]
            node.image = farm_image
            user = node.image_user
            for attr, value in plan.image_user(start, end).items():
                setattr(user, attr, value)
            user.use_auto_refresh = True
            user.use_cyclic = False
            images.append([kind, tree_name, node_name, live.name, farm_image.name])
        keyed = plan.varying(self.values)
        # The IDs the keys go on that have no action yet: drop() takes the action it makes away.
        new_actions = sorted({n for n in map(_owner_id_name, keyed) if not _has_action(_owner_id(n))})
        prefs = bpy.context.preferences.edit
        interpolation = prefs.keyframe_new_interpolation_type
        prefs.keyframe_new_interpolation_type = "CONSTANT"
        try:
            for name in keyed:
                owner, prop = _owner(name)
                for f, values in zip(self.frames, self.values):
                    _assign(owner, prop, values[name])
                    owner.keyframe_insert(prop, frame=f)
        finally:
            prefs.keyframe_new_interpolation_type = interpolation
        scene[RECORD] = plan.encode(
            {
                "version": plan.VERSION,
                "start": start,
                "end": end,
                "frames": {str(f): k for f, k in self.keys.items()},
                "images": images,
                "keyed": keyed,
                "new_actions": new_actions,
            }
        )
        scene.frame_set(self.current)
        return len(keyed)


def _check_updated(scene, depsgraph, frame):
    """Raises UserError when the add-on's frame handlers could not bring the frame's sky or
    aerial table up to date (their failure is in the status lines)."""
    settings = scene.world.welkin
    if settings.auto_update:
        request, _lamp, _warnings = scene_sun.request_for(scene, settings, depsgraph)
        if update.sky_key(settings, request, update.clouds_of(scene, depsgraph)) != settings.last_key:
            raise UserError(f"frame {frame}: the sky was not updated: {settings.status}")
    if scene.welkin_aerial.enabled:
        from .aerial import pass_files

        text = pass_files.at_frame.get(scene.name, {}).get(frame)
        if not isinstance(text, str):
            raise UserError(
                f"frame {frame}: the aerial table was not baked: {text or scene.welkin_aerial.status}"
            )


def _owner(name):
    """(the struct, the property) a snapshot name stands for."""
    kind, owner_name, node_name, what = name.split("\t")
    if kind == "lamp":
        return bpy.data.objects[owner_name].data, what
    return _tree(kind, owner_name).nodes[node_name].inputs[int(what)], "default_value"


def _owner_id_name(name):
    """ "kind\towner" of the ID a snapshot name's keys go on."""
    kind, owner_name = name.split("\t")[:2]
    return f"{kind}\t{owner_name}"


def _owner_id(id_name):
    """The ID (lamp data, world node tree, node group) of _owner_id_name's text, or None."""
    kind, owner_name = id_name.split("\t")
    if kind == "lamp":
        ob = bpy.data.objects.get(owner_name)
        return ob.data if ob is not None else None
    return _tree(kind, owner_name)


def _has_action(id_):
    return id_ is not None and id_.animation_data is not None and id_.animation_data.action is not None


def _remove_empty_actions(id_names):
    """After the bake's keys are deleted: the actions the bake assigned, now animating
    nothing of their ID, are unassigned (and removed when nothing else uses them)."""
    for id_name in id_names:
        id_ = _owner_id(id_name)
        if not _has_action(id_):
            continue
        action = id_.animation_data.action
        if compat.animates_nothing(id_.animation_data):
            id_.animation_data.action = None
            if action.users == 0:
                bpy.data.actions.remove(action)


def _assign(owner, prop, value):
    setattr(owner, prop, value)


def _write_exr(image, path):
    """Writes the image's pixels to `path` as the OpenEXR file Blender packs them into
    (sky/images.pack: full float, lossless), through a temporary image, so that the file
    reloads exactly as the packed image of a static scene does."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    w, h = image.size
    tmp = bpy.data.images.new("Welkin Farm Bake Writer", w, h, alpha=True, float_buffer=True)
    try:
        tmp.alpha_mode = image.alpha_mode
        buf = np.empty(w * h * 4, dtype=np.float32)
        image.pixels.foreach_get(buf)
        tmp.pixels.foreach_set(buf)
        tmp.file_format = "OPEN_EXR"
        tmp.pack()
        data = tmp.packed_file.data
    finally:
        bpy.data.images.remove(tmp)
    partial = path + ".partial"
    with open(partial, "wb") as f:
        f.write(data)
    os.replace(partial, path)


def _sequence_image(scene, live, rel_path):
    name = f"{live.name} (farm)"
    old = bpy.data.images.get(name)
    if old is not None and old.get(MARK):
        bpy.data.images.remove(old)
    image = bpy.data.images.new(name, 1, 1, alpha=True, float_buffer=True)
    image.source = "SEQUENCE"
    image.filepath = rel_path
    image.colorspace_settings.name = live.colorspace_settings.name
    image.alpha_mode = live.alpha_mode
    image[MARK] = scene.name
    image.reload()
    return image


def _live_image(name):
    """The add-on's live aerial image `name` again (a file saved with a bake holds none:
    nothing used it); the next bake of the frame fills it."""
    aerial_scene.baked.clear()
    if name in aerial_frame.SCREEN_IMAGES:
        return aerial_frame.screen_image(name, 1, 1)
    if name == aerial_frame.IMAGE:
        return aerial_frame.table_image()
    return None


def drop(scene, reason=None):
    """Takes the scene's bake out: the add-on's nodes read the live images again, the keys
    the bake added are deleted, the sequence images removed (their files stay on disk).
    Returns True when there was one."""
    rec = record(scene)
    if rec is None:
        if RECORD in scene:
            del scene[RECORD]
        return False
    for kind, tree_name, node_name, live_name, farm_name in rec["images"]:
        tree = _tree(kind, tree_name)
        node = tree.nodes.get(node_name) if tree is not None else None
        live = bpy.data.images.get(live_name) or _live_image(live_name)
        if node is not None and live is not None:
            node.image = live
        farm_image = bpy.data.images.get(farm_name)
        if farm_image is not None and farm_image.get(MARK) and farm_image.users == 0:
            bpy.data.images.remove(farm_image)
    for name in rec["keyed"]:
        try:
            owner, prop = _owner(name)
        except (KeyError, AttributeError, IndexError, ValueError):
            continue
        for f in plan.frames_of(rec["start"], rec["end"]):
            try:
                owner.keyframe_delete(prop, frame=f)
            except RuntimeError:
                pass
    _remove_empty_actions(rec.get("new_actions", []))
    del scene[RECORD]
    if reason:
        print(f"Welkin: Bake for Farm dropped for scene '{scene.name}': {reason}")
    return True


# --- the operators -----------------------------------------------------------------------


def _report(operator, level, text):
    operator.report({level}, f"Welkin: {text}")
    print(f"Welkin: {'error: ' if level == 'ERROR' else ''}{text}")


class WELKIN_OT_bake_farm(bpy.types.Operator):
    """Bake the sky, the sun lamp and the aerial perspective of every frame of the scene's
    range into the file (keys) and beside it (//welkin_farm/ images), so that a Blender
    without Welkin renders the animation as the add-on does. ESC cancels"""

    bl_idname = "welkin.bake_farm"
    bl_label = "Bake for Farm"
    bl_options = {"REGISTER"}

    _bake = None
    _timer = None

    def _start(self, context):
        try:
            self._bake = Bake(context.scene)
        except UserError as error:
            _report(self, "ERROR", f"Bake for Farm: {error}")
            return False
        context.window_manager.progress_begin(0, len(self._bake))
        return True

    def _step(self, context):
        """One frame; returns a finished operator's set, or None to go on."""
        wm = context.window_manager
        try:
            done = self._bake.step()
        except (UserError, ValueError, OSError, RuntimeError) as error:
            self._bake.cancel()
            wm.progress_end()
            _report(self, "ERROR", f"Bake for Farm failed, nothing kept: {error}")
            return {"CANCELLED"}
        except KeyboardInterrupt:
            self._bake.cancel()
            wm.progress_end()
            _report(self, "WARNING", "Bake for Farm cancelled, nothing kept")
            return {"CANCELLED"}
        wm.progress_update(self._bake.index)
        if not done:
            return None
        keyed = self._bake.finish()
        wm.progress_end()
        bake = self._bake
        _report(
            self,
            "INFO",
            f"Bake for Farm: frames {bake.frames[0]}-{bake.frames[-1]} baked "
            f"({len(bake.written)} images in //{plan.FOLDER}/, {keyed} values keyed)",
        )
        context.scene.welkin_aerial.status = (
            f"baked for farms: frames {bake.frames[0]}-{bake.frames[-1]}; ship the folder "
            f"{plan.FOLDER}/ with the .blend"
        )
        return {"FINISHED"}

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        while True:
            result = self._step(context)
            if result is not None:
                return result

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        if not self._start(context):
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        wm = context.window_manager
        if event.type == "ESC":
            wm.event_timer_remove(self._timer)
            self._bake.cancel()
            wm.progress_end()
            _report(self, "WARNING", "Bake for Farm cancelled, nothing kept")
            return {"CANCELLED"}
        if event.type != "TIMER" or event.timer is not self._timer:
            return {"PASS_THROUGH"}
        result = self._step(context)
        if result is None:
            return {"RUNNING_MODAL"}
        wm.event_timer_remove(self._timer)
        return result


class WELKIN_OT_clear_farm_bake(bpy.types.Operator):
    """Take the farm bake out: the add-on computes every frame again (the images in
    //welkin_farm/ stay on disk)"""

    bl_idname = "welkin.clear_farm_bake"
    bl_label = "Clear Farm Bake"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        if not drop(context.scene, "cleared"):
            _report(self, "WARNING", "no farm bake in this scene")
            return {"CANCELLED"}
        context.scene.welkin_aerial.status = "farm bake cleared"
        return {"FINISHED"}


classes = (WELKIN_OT_bake_farm, WELKIN_OT_clear_farm_bake)
