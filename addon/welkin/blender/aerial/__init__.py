# SPDX-License-Identifier: GPL-3.0-or-later
"""Aerial perspective for camera renders (Scene.welkin_aerial, Properties > Render >
Welkin Aerial Perspective). Off by default.

On, it hazes the frame Blender renders itself, in Cycles and EEVEE (F12, `-f`, `-a`, any
`-o`, the Composite / Group Output node and File Output nodes): frame.py adds a node
group to every material that samples the frame's aerial-perspective table and writes two
shader AOVs, and a compositor group that applies Image x T + Inscatter after the Render
Layers node. The table is baked for each frame's camera, sun and atmosphere in
frame_change_post, with the render's own depsgraph, before the frame renders (no frame of
delay). Disabling takes everything out again.

"Write pass files" (off by default) adds, as before, files beside each render from the
render's Z pass (scene_export.frame_path, from scene.render.filepath and the frame):
  welkin_scene_NNNN.json      the frame's SceneDescription (reproduces it with
                              `welkin aerial --scene ... --depth welkin_render_NNNN.exr
                              --depth-channel Depth.V`)
  welkin_aerial_NNNN.exr      Welkin.AerialInscatter.RGB, Welkin.AerialTransmittance.RGB
                              (and the cloud passes, clouds marched up to the geometry)
  welkin_composite_NNNN.exr   R G B: Image x Transmittance + Inscatter (and the clouds over
                              it; the render layer's Image, before the user's compositing)
A file that exists and was not written by the add-on is never replaced: the frame is
reported instead. Problems (no camera, a fisheye camera, no sun lamp, no Z pass) are
printed and shown in the panel's status line; a handler never raises. In a command-line
render (`blender -b file.blend -a`) such a frame fails (blender/farm.py): Blender stops, the frame's
file is not left on disk, and the exit status is non-zero.

  properties.py   Scene.welkin_aerial         panel.py     the Render panel
  scene.py        on, off, bake, scene JSON   frame.py     the material and compositor groups
  pass_files.py   Write Pass Files            compositor.py  its File Output node
  handlers.py     the handlers and the registration
"""
