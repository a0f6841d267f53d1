# SPDX-License-Identifier: GPL-3.0-or-later
"""Ground Shadows: the clouds' moving shadows on the scene, through a shadow layer.

The layer is a square plane of the add-on's own ("Welkin Cloud Shadows"), Ground Shadow
Height above the scene origin (above the props, below the clouds) and Ground Shadow Extent
wide, centred on the origin. Its material is a Transparent BSDF whose colour is the
shadow map: the clouds' transmittance towards the sun from each point of the plane
(welkin.cloud_transmittance, the same clouds the world shows, in a scene centred on the
scene origin), so a ray from the ground towards the sun that crosses the plane at q is
dimmed by T(q), which is the T of the ground point below it (the same line beyond the
plane: nothing else lies between them). Only rays along the sun's direction are dimmed:
the material's transparency is 1 unless the ray's incoming direction is within
GATE_DEG of the direction away from the sun (Geometry > Incoming), so the world's light
reaching the ground through the plane from the rest of the sky (the cloudy world holds
those clouds already) passes unchanged. In Cycles the plane is visible to shadow rays
only (Object > Visibility: camera, diffuse, glossy, transmission and volume rays off).
EEVEE: the material's blend and shadow modes are set to hashed transparency where the
Blender version has them (compat.py).

The map is recomputed with the sky (each frame in animation, so wind moves the shadows);
the object, its mesh, material and image carry SHADOW_KEY and are removed exactly
(Ground Shadows off, Remove Sky): nothing of the user's is changed.
"""

import math

import bpy
import numpy as np

from .. import compat

SHADOW_KEY = "welkin_cloud_shadows"  # on the add-on's object, mesh, material and image: the world
NAME = "Welkin Cloud Shadows"
GATE_DEG = 2.0  # the cone around the sun's direction whose rays the map dims


def map_points(extent_m, height_m, n):
    """The (n * n, 3) points of the map's texel centres, rows from -y to +y (the image's
    rows bottom first), columns from -x to +x."""
    c = (np.arange(n) + 0.5) / n * extent_m - 0.5 * extent_m
    x, y = np.meshgrid(c, c, indexing="xy")
    return np.stack([x.ravel(), y.ravel(), np.full(n * n, float(height_m))], axis=-1)


def shadow_map(native, shadow_json, extent_m, height_m, n, progress=None):
    """(n, n) float32, rows bottom first: T towards the sun at each texel's point."""
    t = native.cloud_transmittance(
        native.SceneDescription.from_json_string(shadow_json),
        map_points(extent_m, height_m, n),
        progress=progress,
    )
    return np.asarray(t, dtype=np.float32).reshape(n, n)


def _ours(id_, world):
    return id_ is not None and id_.get(SHADOW_KEY) == world.name_full


def find(world):
    """The world's shadow layer object, or None."""
    for ob in bpy.data.objects:
        if _ours(ob, world):
            return ob
    return None


def _material(world, image, sun_direction):
    mat = next((m for m in bpy.data.materials if _ours(m, world)), None)
    if mat is None:
        mat = bpy.data.materials.new(NAME)
        mat[SHADOW_KEY] = world.name_full
        tree = compat.material_node_tree(mat)
        nodes, links = tree.nodes, tree.links
        nodes.clear()
        out = nodes.new("ShaderNodeOutputMaterial")
        bsdf = nodes.new("ShaderNodeBsdfTransparent")
        tex = nodes.new("ShaderNodeTexImage")
        tex.name = "Shadow Map"
        tex.interpolation = "Linear"
        tex.extension = "EXTEND"
        uv = nodes.new("ShaderNodeTexCoord")
        geometry = nodes.new("ShaderNodeNewGeometry")
        dot = nodes.new("ShaderNodeVectorMath")
        dot.name = "Away From Sun"
        dot.operation = "DOT_PRODUCT"
        gate = nodes.new("ShaderNodeMath")
        gate.operation = "GREATER_THAN"
        gate.inputs[1].default_value = math.cos(math.radians(GATE_DEG))
        opacity = nodes.new("ShaderNodeMath")  # 1 - T
        opacity.operation = "SUBTRACT"
        opacity.inputs[0].default_value = 1.0
        gated = nodes.new("ShaderNodeMath")  # gate x (1 - T)
        gated.operation = "MULTIPLY"
        shade = nodes.new("ShaderNodeMath")  # 1 - gate x (1 - T)
        shade.operation = "SUBTRACT"
        shade.inputs[0].default_value = 1.0
        links.new(uv.outputs["UV"], tex.inputs["Vector"])
        links.new(geometry.outputs["Incoming"], dot.inputs[0])
        links.new(dot.outputs["Value"], gate.inputs[0])
        links.new(tex.outputs["Color"], opacity.inputs[1])
        links.new(opacity.outputs["Value"], gated.inputs[0])
        links.new(gate.outputs["Value"], gated.inputs[1])
        links.new(gated.outputs["Value"], shade.inputs[1])
        links.new(shade.outputs["Value"], bsdf.inputs["Color"])
        links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
        compat.set_hashed_transparency(mat)
    nodes = mat.node_tree.nodes
    nodes["Shadow Map"].image = image
    # Incoming points back along the ray: a ray from the ground towards the sun arrives
    # with Incoming = -sun.
    away = tuple(-float(c) for c in sun_direction)
    if tuple(nodes["Away From Sun"].inputs[1].default_value) != away:
        nodes["Away From Sun"].inputs[1].default_value = away
    return mat


def _image(world, n):
    image = next((i for i in bpy.data.images if _ours(i, world)), None)
    if image is not None and tuple(image.size) != (n, n):
        bpy.data.images.remove(image)
        image = None
    if image is None:
        image = bpy.data.images.new(NAME, n, n, alpha=False, float_buffer=True)
        image[SHADOW_KEY] = world.name_full
        compat.set_non_color(image)
    return image


def _object(scene, world, extent_m, height_m):
    ob = find(world)
    h, e = float(height_m), 0.5 * float(extent_m)
    verts = [(-e, -e, h), (e, -e, h), (e, e, h), (-e, e, h)]
    if ob is None:
        mesh = bpy.data.meshes.new(NAME)
        mesh[SHADOW_KEY] = world.name_full
        mesh.from_pydata(verts, [], [(0, 1, 2, 3)])
        uv = mesh.uv_layers.new(name="UVMap")
        for loop, value in zip(uv.data, ((0, 0), (1, 0), (1, 1), (0, 1))):
            loop.uv = value
        ob = bpy.data.objects.new(NAME, mesh)
        ob[SHADOW_KEY] = world.name_full
        for ray in ("camera", "diffuse", "glossy", "transmission", "volume_scatter"):
            setattr(ob, f"visible_{ray}", False)
        ob.visible_shadow = True
        ob.hide_select = True
    elif [tuple(v.co) for v in ob.data.vertices] != verts:
        for v, co in zip(ob.data.vertices, verts):
            v.co = co
        ob.data.update()
    if scene.collection.objects.get(ob.name) is None:
        scene.collection.objects.link(ob)
    return ob


def install(scene, shadow, sun_direction, extent_m, height_m, *, create=True):
    """Writes the shadow map `shadow` ((n, n), rows bottom first) into the world's shadow
    layer, making it if needed (main thread). create=False (during a render, where adding
    objects is not safe): only an existing layer's map and sun are updated; returns False
    when there is none."""
    world = scene.world
    n = shadow.shape[0]
    if not create:
        ob = find(world)
        image = next((i for i in bpy.data.images if _ours(i, world)), None)
        if ob is None or image is None or tuple(image.size) != (n, n):
            return False
        _write(image, shadow)
        _material(world, image, sun_direction)
        return True
    image = _image(world, n)
    _write(image, shadow)
    mat = _material(world, image, sun_direction)
    ob = _object(scene, world, extent_m, height_m)
    if ob.data.materials[:] != [mat]:
        ob.data.materials.clear()
        ob.data.materials.append(mat)
    return True


def _write(image, shadow):
    n = shadow.shape[0]
    rgba = np.ones((n, n, 4), dtype=np.float32)
    rgba[..., :3] = shadow[..., None]
    image.pixels.foreach_set(rgba.ravel())
    image.update()


def remove(world):
    """Removes the world's shadow layer: its object, mesh, material and image."""
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.images):
        for id_ in [i for i in collection if _ours(i, world)]:
            collection.remove(id_)
