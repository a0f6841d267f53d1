# SPDX-License-Identifier: GPL-3.0-or-later
"""The world's float images: created by the add-on, filled from the core's top-row-first
arrays (flipped once, in pixels.py), packed into the .blend so they survive saving and
farm rendering. Packing a float image stores it as OpenEXR (full float), so the radiance
reloads unchanged.

Each world owns its images: the image's OWNER_KEY names the world (name_full) that made or
last claimed it. World.copy() copies the world's pointers to them, so a copy given to
another scene would rewrite the original's pixels; ensure() sees that another world that
shows the image is its owner, leaves that image alone and gives the copy its own. An
image whose owner shows it no more (the world renamed, a file from before the key) is
claimed by the world that updates it."""

import bpy

from ... import pixels
from .. import compat

ROLE_KEY = "welkin_role"  # custom property marking the add-on's own images
OWNER_KEY = "welkin_world"  # the name_full of the world the image belongs to
NAMES = {"sky": "Welkin Sky"}


def _linear(image, color_space):
    """Tags `image` with the linear space its pixels are in (compat.image_color_space), so
    that Blender converts them to the file's working space exactly (none when they are in
    it already). Set only when it differs: assigning it frees the image's buffers (a packed
    image is then decoded again, ~0.2 s at 2048 x 1024)."""
    name = compat.image_color_space(image, color_space)
    if image.colorspace_settings.name != name:
        image.colorspace_settings.name = name


def _owned_elsewhere(image, world):
    """True when `image` belongs to another world that shows it (`world` is a copy)."""
    owner = image.get(OWNER_KEY)
    if owner == world.name_full:
        return False
    return any(
        other != world and other.name_full == owner and image == other.welkin.sky_image
        for other in bpy.data.worlds
    )


def owned(settings):
    """True when the world's image is its own to write (not another world's)."""
    image = settings.sky_image
    return image is None or bool(image.get(ROLE_KEY) and not _owned_elsewhere(image, settings.id_data))


def ensure(settings, role, width, height, color_space="rec709"):
    """The add-on's image for `role` ("sky") at width x height, the world's own, tagged with
    `color_space` (the linear space of the pixels it will get)."""
    attr = "sky_image"
    world = settings.id_data
    image = getattr(settings, attr)
    if image is not None and image.get(ROLE_KEY) != role:
        image = None  # never write into an image the add-on did not make
    if image is not None and _owned_elsewhere(image, world):
        image = None  # another world's (this one is its copy): a new image of its own
    if image is not None and tuple(image.size) != (width, height):
        if image.packed_file is not None:
            image.unpack(method="REMOVE")
        image.scale(width, height)
    if image is None:
        image = bpy.data.images.new(NAMES[role], width, height, alpha=False, float_buffer=True)
        image[ROLE_KEY] = role
        setattr(settings, attr, image)
    if image.get(OWNER_KEY) != world.name_full:
        image[OWNER_KEY] = world.name_full
    _linear(image, color_space)
    return image


# RGBA buffers kept between live updates, per (image name, size).
_buffers = {}


def write(image, top_first):
    """Fills `image` from an (H, W, 3) top-row-first array."""
    h, w, _ = top_first.shape
    key = (image.name, w, h)
    if key not in _buffers:
        if len(_buffers) > 4:
            _buffers.clear()
        _buffers[key] = pixels.rgba_buffer(w, h)
    flat = pixels.to_blender(top_first, _buffers[key])
    # Setting pixels marks the image dirty and drops its GPU textures; update_tag() tells
    # the depsgraph (and so Cycles' viewport render). Image.update() is not called: it
    # builds the 8-bit display buffer, which nothing here needs and costs ~0.1 s at 2048.
    image.pixels.foreach_set(flat)
    image.update_tag()


def pack(image):
    """Packs the image's current pixels into the .blend (as OpenEXR, float)."""
    image.file_format = "OPEN_EXR"
    image.pack()


def drop_disc_image(settings):
    """Forgets the sun-disc image of a file saved before the world's nodes drew the disc
    (and deletes it once nothing else uses it)."""
    image = settings.disc_image
    if image is not None:
        settings.disc_image = None
        if image.get(ROLE_KEY) == "disc" and image.users == 0:
            bpy.data.images.remove(image)


def remove(settings):
    for attr in ("sky_image", "disc_image"):
        image = getattr(settings, attr)
        setattr(settings, attr, None)
        if image is not None and image.get(ROLE_KEY) and image.users == 0:
            bpy.data.images.remove(image)
