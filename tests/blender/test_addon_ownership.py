# SPDX-License-Identifier: Apache-2.0
"""What the add-on owns and what it gives back (issue 18, items 1, 2 and 9):

(1) A copied world (World.copy(), given to another scene with another sun) gets images of
    its own on its first update: the original's pixels stay bit-identical, each world
    shows its own sun's sky, and the user's images are never written.
(2) A world linked from a library (a real library .blend made here) is refused by
    update_sky and remove_sky with a report naming the world and the library, from the
    frame handler with a printed message; nothing changes: no image is made, and after
    saving and reopening there is no orphan image and the world is still the library's.
(9) remove_sky gives the sun lamp back the colour, strength and angle Sync Lamp changed,
    exactly (bit for bit), also after several updates that moved the sun; a lamp the
    user changed after turning Sync Lamp off keeps the user's values.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
atm = welkin.Atmosphere.preset(welkin.Atmosphere.preset_names()[0])  # the add-on's default


def expect_error(fragments, operator):
    try:
        operator()
    except RuntimeError as error:
        for fragment in fragments:
            T.check(fragment in str(error), f"report {str(error)!r} does not name {fragment!r}")
        print(f"reported: {str(error).strip()}")
        return
    raise AssertionError(f"{operator} did not fail (expected {fragments})")


# (9) The lamp's own values come back exactly.
scene, sun = T.new_scene(30.0, 40.0, resolution="256")
sun.data.energy = 3.25
sun.data.color = (0.9, 0.7, 0.35)
sun.data.angle = 0.1234
before = (tuple(sun.data.color), sun.data.energy, sun.data.angle)
bpy.ops.welkin.update_sky()
T.check(sun.data.energy != 3.25 and sun.data.angle != before[2], "Sync Lamp changed nothing")
T.aim_sun(sun, 12.0, 100.0)
bpy.context.view_layer.update()
bpy.ops.welkin.update_sky()
bpy.ops.welkin.remove_sky()
after = (tuple(sun.data.color), sun.data.energy, sun.data.angle)
T.check(after == before, f"remove_sky left the lamp at {after}, it was {before}")
T.check("welkin_lamp_original" not in sun.data, "the kept lamp values stayed on the Light")
# Sync Lamp off: the lamp is not touched, and remove_sky leaves it as it is.
scene.world.welkin.sync_lamp = False
bpy.ops.welkin.update_sky()
T.check((tuple(sun.data.color), sun.data.energy, sun.data.angle) == before, "Sync Lamp off changed the lamp")
bpy.ops.welkin.remove_sky()
# The user takes the lamp over (Sync Lamp off, a new strength): remove_sky keeps theirs.
scene.world.welkin.sync_lamp = True
bpy.ops.welkin.update_sky()
scene.world.welkin.sync_lamp = False
sun.data.energy = 7.5
bpy.ops.welkin.remove_sky()
T.check(sun.data.energy == 7.5, f"remove_sky undid the user's own lamp strength: {sun.data.energy}")
T.check(
    not any(k.startswith("welkin_lamp") for k in sun.data.keys()),
    f"kept lamp values stayed on the Light: {list(sun.data.keys())}",
)
scene.world.welkin.sync_lamp = True
print("(9) remove_sky restores the lamp's colour, strength and angle exactly")

# (1) A copied world given to another scene with another sun.
bpy.ops.welkin.update_sky()
world_a = scene.world
user_image = bpy.data.images.new("User Image", 8, 4, float_buffer=True)
user_pixels = np.full(8 * 4 * 4, 0.25, dtype=np.float32)
user_image.pixels.foreach_set(user_pixels)
world_a.welkin.sky_image["note"] = "the original's"
scene_b = bpy.data.scenes.new("Scene B")
sun_b = bpy.data.objects.new("Sun B", bpy.data.lights.new("Sun B", "SUN"))
scene_b.collection.objects.link(sun_b)
T.aim_sun(sun_b, 5.0, 200.0)
world_b = world_a.copy()
scene_b.world = world_b
T.check(
    world_b.welkin.sky_image == world_a.welkin.sky_image,
    "World.copy() no longer shares the image pointers: this test tests nothing",
)
pixels_a = T.world_pixels(world_a.welkin.sky_image).copy()


def update_scene(s):
    # Scripts run here without a window: update_sky takes the scene from the context.
    from welkin.blender.sky import update

    depsgraph = s.view_layers[0].depsgraph
    s.view_layers[0].update()
    return update.update_sky(s, depsgraph, force=False, pack=True)


update_scene(scene_b)
T.check(world_b.welkin.sky_image != world_a.welkin.sky_image, "the copy still shows the original's image")
np.testing.assert_array_equal(
    T.world_pixels(world_a.welkin.sky_image), pixels_a, err_msg="the copy's update rewrote the original's sky"
)
s_b = tuple(sun_b.matrix_world.col[2][:3])
ref_b = welkin.sky_image(atm, 0.0, s_b, 256, "auto", sun_disc=False)
np.testing.assert_allclose(
    T.world_pixels(world_b.welkin.sky_image),
    ref_b,
    rtol=1e-6,
    err_msg="the copy does not show its own sun's sky",
)
tex = [n for n in world_b.node_tree.nodes if n.get("welkin_role") == "sky_texture"]
T.check(
    len(tex) == 1 and tex[0].image == world_b.welkin.sky_image,
    "the copy's node tree does not show its own image",
)
tex_a = [n for n in world_a.node_tree.nodes if n.get("welkin_role") == "sky_texture"]
T.check(tex_a[0].image == world_a.welkin.sky_image, "the original's nodes were repointed")
# And the other way: the original's update leaves the copy's pixels alone.
pixels_b = T.world_pixels(world_b.welkin.sky_image).copy()
T.aim_sun(sun, 50.0, 10.0)
bpy.context.view_layer.update()
bpy.ops.welkin.update_sky()
np.testing.assert_array_equal(
    T.world_pixels(world_b.welkin.sky_image), pixels_b, err_msg="the original's update rewrote the copy's sky"
)
s_a = tuple(sun.matrix_world.col[2][:3])
np.testing.assert_allclose(
    T.world_pixels(world_a.welkin.sky_image),
    welkin.sky_image(atm, 0.0, s_a, 256, "auto", sun_disc=False),
    rtol=1e-6,
)
T.check(world_a.welkin.sky_image.get("note") == "the original's", "the original lost its image")
# A copy whose sky is current (same key) still gets images of its own at its update.
world_c = world_a.copy()
scene_c = bpy.data.scenes.new("Scene C")
scene_c.collection.objects.link(sun)  # the same sun: the copy's key is current
scene_c.world = world_c
update_scene(scene_c)
T.check(
    world_c.welkin.sky_image not in (world_a.welkin.sky_image, world_b.welkin.sky_image),
    "a copy with a current key kept the original's image",
)
flat = np.empty(8 * 4 * 4, dtype=np.float32)
user_image.pixels.foreach_get(flat)
np.testing.assert_array_equal(flat, user_pixels, err_msg="the user's image was written")
# Renaming the original keeps its images (claimed again, not replaced).
image_a = world_a.welkin.sky_image
world_a.name = "Renamed World"
T.aim_sun(sun, 45.0, 10.0)
bpy.context.view_layer.update()
bpy.ops.welkin.update_sky()
T.check(world_a.welkin.sky_image == image_a, "renaming the world replaced its image")
T.check(image_a.get("welkin_world") == world_a.name_full, "the renamed world did not claim it")
# Removing the copy's sky leaves the original's images and nodes.
from welkin.blender.sky import update  # noqa: E402

update.remove_sky(scene_b)
T.check(
    world_a.welkin.sky_image == image_a and image_a.name in bpy.data.images,
    "removing the copy's sky took the original's image",
)
print("(1) a copied world gets its own images; neither world rewrites the other's pixels")

# (2) A world linked from a library.
for s in (scene_b, scene_c):
    bpy.data.scenes.remove(s)
for w in (world_b, world_c):  # the copies and their images go (not this item's business)
    doomed = [i for i in (w.welkin.sky_image,) if i is not None]
    bpy.data.worlds.remove(w)
    for i in doomed:
        bpy.data.images.remove(i)
bpy.ops.welkin.remove_sky()
lib_path = T.TMP / "library.blend"
lib_world = bpy.data.worlds.new("Library World")
lib_world.use_fake_user = True
scene.world = lib_world
bpy.ops.welkin.update_sky()  # a library world that has a Welkin sky of its own
lib_sky = T.world_pixels(lib_world.welkin.sky_image).copy()
lib_images = [lib_world.welkin.sky_image]
scene.world = world_a
bpy.data.libraries.write(str(lib_path), {lib_world}, fake_user=True)
bpy.data.worlds.remove(lib_world)
for i in lib_images:
    bpy.data.images.remove(i)
bpy.ops.wm.save_as_mainfile(filepath=str(T.TMP / "user.blend"))
with bpy.data.libraries.load(str(lib_path), link=True) as (src, dst):
    dst.worlds = ["Library World"]
linked = dst.worlds[0]
T.check(linked.library is not None, "the world was not linked")
scene.world = linked
T.aim_sun(sun, 20.0, 300.0)  # another sun: the linked sky is stale
bpy.context.view_layer.update()
images_before = sorted(i.name_full for i in bpy.data.images)
expect_error(["Library World", "library.blend", "linked"], bpy.ops.welkin.update_sky)
expect_error(["Library World", "library.blend"], bpy.ops.welkin.remove_sky)
T.check(
    sorted(i.name_full for i in bpy.data.images) == images_before,
    f"update_sky on a linked world made images: {sorted(bpy.data.images.keys())}",
)
T.check(
    not any(
        n.get("welkin_role") == "sky_texture" and n.image is not None and n.image.library is None
        for n in linked.node_tree.nodes
    ),
    "the linked world's nodes show a local image",
)
# The frame handler (auto update on, the library's sky active) refuses too, printed.
from welkin.blender import handlers  # noqa: E402

T.check(linked.welkin.active and linked.welkin.auto_update, "the library's sky is not live")
T.check(handlers._run(scene, None, pack=False) is not None, "the handler updated a linked world")
scene.frame_set(2)  # frame_change_post runs; it must not raise
from welkin.blender.sky import background  # noqa: E402
from welkin.blender.sky.scene_sun import UserError  # noqa: E402

try:
    background.start(scene)  # the UI's cloudy-sky job refuses it as well
    raise AssertionError("background.start accepted a linked world")
except UserError as error:
    T.check("Library World" in str(error), f"background.start: {error}")
np.testing.assert_array_equal(
    T.world_pixels(linked.welkin.sky_image), lib_sky, err_msg="the linked world's sky changed"
)
bpy.ops.wm.save_as_mainfile(filepath=str(T.TMP / "user.blend"))
bpy.ops.wm.open_mainfile(filepath=str(T.TMP / "user.blend"))
scene = bpy.context.scene
T.check(
    scene.world.library is not None and scene.world.name == "Library World",
    "the saved file does not link the library's world",
)
orphans = [
    i.name
    for i in bpy.data.images
    if i.users == 0
    or (
        i.library is None
        and i.get("welkin_role")
        and not any(i == w.welkin.sky_image for w in bpy.data.worlds)
    )
]
T.check(not orphans, f"orphan images after save and reopen: {orphans}")
np.testing.assert_array_equal(
    T.world_pixels(scene.world.welkin.sky_image),
    lib_sky,
    err_msg="the linked world's sky is gone after reopening",
)
print("(2) a linked world is refused with its name and library; nothing changes")

T.done("test_addon_ownership")
