# SPDX-License-Identifier: Apache-2.0
"""Headless Blender + Cycles: the add-on's aerial perspective, end to end.

A ground plane and cubes out to 30 km, camera 20 m up looking along +X, `hazy` air; with
Scene.welkin_aerial enabled, `render(animation=True)` for 2 frames must leave, per frame,
the scene JSON, the passes EXR and the composited EXR beside the render, and:
  * far pixels (depth > 10 km) have a lower transmittance and a higher in-scattering than
    near ones (depth < 1 km);
  * the composited file equals Image x T + Inscatter from the render's own Image and the
    passes, to 1e-6 relative (float32 products);
  * `build/welkin aerial --scene <frame json> --depth <frame's depth EXR>` reproduces the
    passes to 1e-5 (same code, same inputs: only the JSON round trip can differ);
  * the user's compositor nodes and links survive enable and disable.
Orthographic and equirectangular frames: the frame Blender wrote (hazed by the material
group) equals the core's composite within 2 % where every sample of a pixel sees the same
depth.
Bad input: no camera, a fisheye camera, the Z pass turned off, and a user's file where the
passes would go: a clear status line, no pass written (or the user's file left alone).
"""

import json
import math
import os
import pathlib
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as at  # noqa: E402

ROOT = at.ROOT


def build_scene():
    scene, sun = at.new_scene(sun_elevation_deg=10.0, sun_azimuth_deg=20.0, camera_z=20.0)
    cam = scene.camera
    cam.rotation_euler = (math.radians(88.0), 0.0, math.radians(-90.0))  # along +X, 2 deg down
    cam.data.clip_end = 1e6
    for frame, z in ((1, 20.0), (2, 60.0)):  # each frame its own camera
        cam.location.z = z
        cam.keyframe_insert("location", index=2, frame=frame)
    bpy.ops.mesh.primitive_plane_add(size=200000.0, location=(0.0, 0.0, 0.0))
    for d, y in ((300.0, -40.0), (3000.0, 0.0), (30000.0, 4000.0)):
        bpy.ops.mesh.primitive_cube_add(size=0.06 * d, location=(d, y, 0.03 * d))
    scene.world.welkin.preset = "hazy"
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = 96, 48
    scene.render.resolution_percentage = 100
    from welkin.blender import compat

    compat.set_file_format(scene.render.image_settings, "OPEN_EXR")
    scene.frame_start, scene.frame_end = 1, 2
    scene.render.filepath = str(at.TMP / "out" / "frame_")
    return scene


def add_user_nodes(scene):
    """The user's compositor: the frame (Render Layers, or a 5.3 effect's Group Input) ->
    "User Curves" -> the output (Composite, or 5.0's Group Output). Returns the output
    node."""
    from welkin.blender import compat

    tree, _undo = compat.ensure_scene_compositor(scene, "User Compositor")
    rl = next((n for n in tree.nodes if n.bl_idname == "CompositorNodeRLayers"), None)
    comp = compat.compositor_output(tree)
    curves = tree.nodes.new("CompositorNodeCurveRGB")
    curves.name = "User Curves"
    tree.links.new(compat.compositor_frame(tree, rl), curves.inputs["Image"])
    tree.links.new(curves.outputs["Image"], comp.inputs[0])
    return tree, comp


def feeder(comp):
    return comp.inputs[0].links[0].from_node.name


def rgb(module, path, names):
    pixels, channels = module.read_exr(str(path))
    return np.stack([pixels[..., channels.index(n)] for n in names], axis=-1)


def frame_matches_the_core(scene, module, base, what):
    """Renders the current frame (pass files on) and compares the frame Blender wrote with
    the core's composite where every sample of a pixel meets the same surface at the same
    depth (the depths within two pixels agree within 1 %) and the air shows (T < 0.95): 2 %."""
    from welkin import scene_export

    bpy.ops.render.render(write_still=True)
    frame_no = scene.frame_current
    path = scene_export.frame_path(base, "aerial", frame_no)
    at.check(pathlib.Path(path).is_file(), f"{what}: no passes ({scene.welkin_aerial.status})")
    tr = rgb(module, path, [f"Welkin.AerialTransmittance.{c}" for c in "RGB"])
    at.check(np.isfinite(tr).all() and tr.min() >= 0.0 and tr.max() <= 1.0, f"{what}: bad T")
    frame = rgb(module, bpy.path.abspath(scene.render.filepath) + ".exr", "RGB")
    composite = rgb(module, scene_export.frame_path(base, "composite", frame_no), "RGB")
    pixels, names = module.read_exr(scene_export.frame_path(base, "render", frame_no))
    z = pixels[..., names.index("Depth.V")].astype(np.float64)
    z = np.where(z < 1e8, z, np.nan)
    # Within two pixels: a pixel filter reaches past a pixel's neighbours' centres, and
    # Blender 4.x's Z pass is one sample's, not the pixel's mean.
    with np.errstate(invalid="ignore"):
        smooth = np.all(
            [
                np.abs(np.roll(np.roll(z, dy, 0), dx, 1) - z) <= 0.01 * z
                for dy in range(-2, 3)
                for dx in range(-2, 3)
            ],
            axis=0,
        )
    smooth[[0, 1, -2, -1], :] = smooth[:, [0, 1, -2, -1]] = False
    hazed = smooth & (tr.mean(-1) < 0.95)
    at.check(hazed.sum() > 20, f"{what}: only {hazed.sum()} hazed pixels to compare")
    err = np.abs(frame - composite)[hazed] / np.maximum(composite[hazed], 1e-6)
    print(
        f"{what} frame vs the core's composite: {hazed.sum()} px, max {err.max():.4f}, mean {err.mean():.5f}"
    )
    at.check(err.max() < 0.02, f"{what}: the frame differs from the core's composite by {err.max()}")
    print(f"ok: {what} camera")


def check_enable(scene, tree, comp, names_before):
    """Enabling keeps the user's compositor and links the depth node to the un-hazed Image."""
    from welkin.blender import compat
    from welkin.blender.aerial import compositor

    scene.welkin_aerial.side_files = True  # the pass files beside the render
    scene.welkin_aerial.enabled = True
    at.check(compat.scene_compositor(scene) == tree, "enable replaced the user's compositor")
    at.check(names_before <= {n.name for n in tree.nodes}, "enable removed a user node")
    at.check(feeder(comp) == "User Curves", "the output is no longer fed by the user's node")
    depth = compositor.depth_node(scene)  # in the user's tree, or (5.3+) Welkin's effect
    at.check(
        depth.inputs["Depth"].is_linked and depth.inputs["Image"].is_linked,
        "the depth node's inputs are not linked",
    )
    at.check(
        depth.inputs["Image"].links[0].from_node.bl_idname == "CompositorNodeRLayers",
        "the depth node does not take the render layer's own (un-hazed) Image",
    )
    at.check(scene.view_layers[0].use_pass_z, "enabling did not turn the Z pass on")


def check_animation(scene, module):
    """Two animated frames: passes, JSON and composite per frame; the CLI reproduces them."""
    from welkin import scene_export

    bpy.ops.render.render(animation=True)
    base = scene_export.file_base(bpy.path.abspath(scene.render.filepath))
    cli = ROOT / "build" / "welkin"
    for frame in (1, 2):
        paths = {k: pathlib.Path(scene_export.frame_path(base, k, frame)) for k in scene_export.KINDS}
        for kind, path in paths.items():
            at.check(
                path.is_file(),
                f"frame {frame}: {kind} file {path} missing (status: {scene.welkin_aerial.status})",
            )
        cam_z = json.loads(paths["scene"].read_text())["camera"]["matrix_world"][2][3]
        at.check(abs(cam_z - 40.0 * frame + 20.0) < 1e-3, f"frame {frame}: camera z {cam_z}")
        pixels, names = module.read_exr(str(paths["render"]))
        depth = pixels[..., next(i for i, n in enumerate(names) if n.startswith("Depth."))]
        image = np.stack([pixels[..., names.index(f"Image.{c}")] for c in "RGB"], axis=-1)
        ins = rgb(module, paths["aerial"], [f"Welkin.AerialInscatter.{c}" for c in "RGB"])
        tr = rgb(module, paths["aerial"], [f"Welkin.AerialTransmittance.{c}" for c in "RGB"])
        near, far = depth < 1000.0, (depth > 10000.0) & (depth < 1e8)
        at.check(
            near.sum() > 20 and far.sum() > 5,
            f"frame {frame}: too few near/far pixels ({near.sum()}, {far.sum()})",
        )
        t_near, t_far = tr[near].mean(), tr[far].mean()
        i_near, i_far = ins[near].mean(), ins[far].mean()
        print(
            f"frame {frame}: T near {t_near:.4f} far {t_far:.4f}; inscatter near {i_near:.5f} far {i_far:.5f}"
        )
        at.check(t_far < t_near - 0.05, f"frame {frame}: far T {t_far} not below near {t_near}")
        at.check(i_far > 2.0 * i_near, f"frame {frame}: far inscatter {i_far} not above {i_near}")
        composite = rgb(module, paths["composite"], "RGB")
        expect = image * tr + ins
        err = np.abs(composite - expect) / np.maximum(np.abs(expect), 1e-6)
        at.check(err.max() < 1e-6, f"frame {frame}: composite differs by {err.max()}")
        out = at.TMP / f"cli_{frame}.exr"
        subprocess.run(
            [
                str(cli),
                "aerial",
                "--scene",
                str(paths["scene"]),
                "--depth",
                str(paths["render"]),
                "--depth-channel",
                "Depth.V",
                "-o",
                str(out),
            ],
            check=True,
        )
        cli_pix, cli_names = module.read_exr(str(out))
        ours, our_names = module.read_exr(str(paths["aerial"]))
        for n in scene_export.PASS_CHANNELS:
            diff = np.abs(cli_pix[..., cli_names.index(n)] - ours[..., our_names.index(n)]).max()
            at.check(diff < 1e-5, f"frame {frame}: CLI {n} differs by {diff}")
    print("ok: 2 frames, passes + JSON + composite, CLI reproduces")
    return base


def check_user_file(scene, base):
    """The user's file where frame 3's passes would go is left alone."""
    from welkin import scene_export

    user = pathlib.Path(scene_export.frame_path(base, "aerial", 3))
    user.write_text("a user's file")
    scene.camera.animation_data_clear()
    scene.frame_set(3)
    bpy.ops.render.render(write_still=True)
    at.check(user.read_text() == "a user's file", "the user's file was replaced")
    at.check("not replaced" in scene.welkin_aerial.status, scene.welkin_aerial.status)
    user.unlink()
    print("ok: a user's file is never replaced")


def check_z_pass_off(scene, module, base):
    """Z pass turned off behind the add-on's back: turned on again, reported or computed."""
    from welkin import scene_export

    scene.frame_set(4)
    scene.view_layers[0].use_pass_z = False
    bpy.ops.render.render(write_still=True)
    at.check(scene.view_layers[0].use_pass_z, "the Z pass was not turned on again")
    wrote = pathlib.Path(scene_export.frame_path(base, "aerial", 4)).is_file()
    if wrote:  # then from the frame's real depth, not the File Output's constant 0
        tr = rgb(
            module,
            scene_export.frame_path(base, "aerial", 4),
            [f"Welkin.AerialTransmittance.{c}" for c in "RGB"],
        )
        at.check(tr.min() < 0.5, f"Z pass off: passes computed without depth (T min {tr.min()})")
    at.check(wrote or "Z pass" in scene.welkin_aerial.status, scene.welkin_aerial.status)
    print(f"ok: Z pass off -> {'computed' if wrote else 'reported'}: {scene.welkin_aerial.status}")


def check_unlinked_depth(scene, base):
    """The Depth link to our File Output node removed: no depth written, reported."""
    from welkin import scene_export
    from welkin.blender.aerial import compositor

    scene.frame_set(9)
    out_node = compositor.depth_node(scene)
    out_node.id_data.links.remove(out_node.inputs["Depth"].links[0])
    bpy.ops.render.render(write_still=True)
    # (3.4 leaves the unlinked input out of the file, 4.5 and 5.0 write it as zeros)
    at.check(
        "no Z pass" in scene.welkin_aerial.status or "Z pass is empty" in scene.welkin_aerial.status,
        scene.welkin_aerial.status,
    )
    at.check(
        not pathlib.Path(scene_export.frame_path(base, "aerial", 9)).exists(),
        "passes written without a Z pass",
    )
    scene.welkin_aerial.enabled = False
    scene.welkin_aerial.enabled = True  # relinks
    at.check(
        compositor.depth_node(scene).inputs["Depth"].is_linked, "toggling did not relink the Depth input"
    )
    print(f"ok: unlinked Z pass reported: {scene.welkin_aerial.status}")


def check_fisheye(scene, base):
    """A fisheye camera: a clear report, no passes."""
    from welkin import scene_export
    from welkin.blender import compat

    scene.frame_set(5)
    scene.camera.data.type = "PANO"
    compat.camera_panorama(scene.camera.data).panorama_type = "FISHEYE_EQUIDISTANT"
    bpy.ops.render.render(write_still=True)
    at.check("FISHEYE" in scene.welkin_aerial.status, scene.welkin_aerial.status)
    at.check(
        not pathlib.Path(scene_export.frame_path(base, "aerial", 5)).exists(), "a fisheye frame got passes"
    )
    print(f"ok: fisheye reported: {scene.welkin_aerial.status}")


def check_ortho_and_pano(scene, module, base):
    """Orthographic and equirectangular frames: the frame Blender wrote equals the core's."""
    from welkin.blender import compat
    from welkin.blender.aerial import frame as aerial_frame

    # Orthographic and equirectangular frames: supported by the core; passes finite, T in
    # [0, 1]; the frame Blender wrote, hazed by the material group (Cycles: the screen table
    # over the Window coordinate), equals the core's composite of the same frame.
    ground = bpy.data.materials.new("Ground")  # a material added late gets the group too
    ground.use_nodes = True
    for ob in scene.objects:
        if ob.type == "MESH" and not ob.data.materials:
            ob.data.materials.append(ground)
    scene.frame_set(6)
    scene.camera.rotation_euler.x = math.radians(90.0)  # level: the 3 km cube's face
    scene.camera.data.type = "ORTHO"
    scene.camera.data.ortho_scale = 200.0
    frame_matches_the_core(scene, module, base, "ortho")
    # Its distance is the depth (View Distance would measure from the camera's centre, which
    # differs from the depth by up to 100 m across this 200 m wide view).
    slice_input = bpy.data.node_groups[aerial_frame.SHADER_GROUP].nodes[aerial_frame.SLICE_NODE].inputs[0]
    at.check(
        slice_input.links[0].from_socket.name == "View Z Depth",
        f"ortho: the group reads {slice_input.links[0].from_socket.name}",
    )
    # Its lattice lies over the Window coordinate (the View Vector is one for the whole frame).
    screen_input = bpy.data.node_groups[aerial_frame.SHADER_GROUP].nodes[aerial_frame.SCREEN_NODE].inputs[0]
    at.check(
        screen_input.links[0].from_socket.name == "Window",
        f"ortho: the group's lattice is over {screen_input.links[0].from_socket.name}",
    )
    scene.camera.data.type = "PANO"
    pano = compat.camera_panorama(scene.camera.data)
    pano.panorama_type = "EQUIRECTANGULAR"
    pano.longitude_min, pano.longitude_max = math.radians(-6.0), math.radians(6.0)
    pano.latitude_min, pano.latitude_max = math.radians(-3.0), math.radians(3.0)
    frame_matches_the_core(scene, module, base, "equirectangular")
    at.check(
        slice_input.links[0].from_socket.name == "View Distance",
        f"equirectangular: the group reads {slice_input.links[0].from_socket.name}",
    )
    scene.camera.rotation_euler.x = math.radians(88.0)


def check_no_camera(scene):
    """No camera: the handler reports, never raises."""
    from welkin.blender.aerial import handlers as aerial_handlers

    scene.frame_set(7)
    camera = scene.camera
    scene.camera = None
    aerial_handlers.on_render_post(scene)
    at.check("no scene camera" in scene.welkin_aerial.status, scene.welkin_aerial.status)
    scene.camera = camera
    print(f"ok: no camera reported: {scene.welkin_aerial.status}")


def check_saved_file(scene):
    """The same from a saved file, rendered by `blender -a` in a fresh process."""
    from welkin import scene_export

    # The same from a saved file, `blender -b file.blend --addons welkin -a` in a fresh
    # process: the setting is saved, the handlers load with the add-on.
    for frame, z in ((1, 20.0), (2, 60.0)):
        scene.camera.location.z = z
        scene.camera.keyframe_insert("location", index=2, frame=frame)
    scene.render.filepath = str(at.TMP / "out2" / "shot_")
    blend = at.TMP / "aerial.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["BLENDER_USER_SCRIPTS"] = str(at.scripts_dir())
    env["BLENDER_USER_CONFIG"] = str(at.TMP / "config")
    run = subprocess.run(
        [*at.blender_command(), "-b", "--factory-startup", str(blend), "--addons", "welkin", "-a"],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    at.check(run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:])
    base2 = scene_export.file_base(str(at.TMP / "out2" / "shot_"))
    for frame in (1, 2):
        for kind in scene_export.KINDS:
            at.check(
                pathlib.Path(scene_export.frame_path(base2, kind, frame)).is_file(),
                f"blender -a: frame {frame} has no {kind} file:\n{run.stdout[-3000:]}{run.stderr[-2000:]}",
            )
        text = pathlib.Path(scene_export.frame_path(base2, "scene", frame)).read_text()
        cam_z = json.loads(text)["camera"]["matrix_world"][2][3]
        at.check(abs(cam_z - (40.0 * frame - 20.0)) < 1e-3, f"blender -a: frame {frame} z {cam_z}")
    print("ok: blender -b file.blend --addons welkin -a")


def check_disable(scene, tree, comp, names_before):
    """Disable: our nodes out, the user's back in place."""
    scene.welkin_aerial.enabled = False
    names = {n.name for n in tree.nodes}
    at.check(names == names_before, f"after disable: {sorted(names ^ names_before)}")
    at.check(feeder(comp) == "User Curves", "disable did not restore the user's link")
    curves = tree.nodes["User Curves"]
    at.check(
        curves.inputs["Image"].links[0].from_node.bl_idname in ("CompositorNodeRLayers", "NodeGroupInput"),
        "disable did not relink the frame to the user's node",
    )
    print("ok: user nodes survive enable/disable")


def main():
    addon, module = at.install_addon()
    scene = build_scene()
    tree, comp = add_user_nodes(scene)
    names_before = {n.name for n in tree.nodes}
    check_enable(scene, tree, comp, names_before)
    base = check_animation(scene, module)
    check_user_file(scene, base)
    check_z_pass_off(scene, module, base)
    check_unlinked_depth(scene, base)
    check_fisheye(scene, base)
    check_ortho_and_pano(scene, module, base)
    check_no_camera(scene)
    scene.frame_set(8)
    scene.camera.data.type = "PERSP"
    check_saved_file(scene)
    check_disable(scene, tree, comp, names_before)
    at.done("test_aerial_render")


main()
