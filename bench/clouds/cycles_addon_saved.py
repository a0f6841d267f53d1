# SPDX-License-Identifier: Apache-2.0
"""The Cycles comparison of tests/blender/test_cycles_clouds_lighting.py, saved once and
replayed: --save renders Cycles and Welkin's reference path tracer in Blender and keeps them
with the engine's scene descriptions and the regions; --load reruns only the engine's cloud
pass (the fast march) against them, outside Blender, in about a second per variant of the
lighting options, for work on the fast march's lighting estimate.

    build/venv-bpy-5.0/bin/python tests/blender/bpy_blender.py -b --factory-startup \
        --python-use-system-env --python bench/clouds/cycles_addon_saved.py -- --save DIR
    PYTHONPATH=build /usr/bin/python3 bench/clouds/cycles_addon_saved.py --load DIR \
        [--lighting '{"sides": false}']

The scene, the views ("side", "backlit") and the regions are the test's (the same calls of
bench/cycles_addon_clouds.py: the lamp at the cloud's altitude, the engine's pass without the
air in front). --load prints, per region of the side view, the fast march over Cycles and
over the reference, and the fast march's light split in two, each over the reference: the
sun's single scattering with the sky (the march with octaves = 1) and the rest, the sun's
multiple scattering; for the backlit view the silver lining (edge over core) of Cycles and
of the fast march. --lighting merges a JSON object into the scene's clouds.lighting (the
options of docs/reference.md's scene file).
"""

import argparse
import json
import os
import sys

import numpy as np

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec.709, as bench/cycles_addon_clouds.py


def save(directory):
    """In Blender: Cycles, the reference (side view) and the engine's scene descriptions."""
    import pathlib

    root = pathlib.Path(__file__).resolve().parents[2]
    sys.path.insert(0, str(root / "bench"))
    sys.path.insert(0, str(root / "tests" / "blender"))
    import addon_testing as T
    import bpy

    _addon, native = T.install_addon()
    import cycles_addon_clouds as ac
    import cycles_volume as cv
    from welkin.blender.engine import render_engine

    os.makedirs(directory, exist_ok=True)
    vdb = os.path.abspath(os.path.join(directory, "cumulus.vdb"))
    ac.write_cloud(vdb)
    for view, (el, az) in ac.TEST_VIEWS.items():
        scene, sun, _ob = ac.build_test_view(T, vdb, el, az)
        ac.update_sky(scene, sun, native, lamp="cloud")
        cyc = cv.render(scene, os.path.join(directory, f"cycles_{view}.exr"))
        desc = json.loads(
            render_engine.scene_description_json(scene, bpy.context.evaluated_depsgraph_get(), native)
        )
        desc.setdefault("aerial", {})["sky_depth_m"] = 1.0  # no air in front: ac.engine_pass(air=False)
        with open(os.path.join(directory, f"scene_{view}.json"), "w") as f:
            json.dump(desc, f)
        regs = ac.regions(scene, cyc[..., 3], ac.sun_direction(el, az))
        ref = (
            ac.reference(scene, native, vdb, ac.TEST_SIGMA, ac.WELKIN_LOBES, ac.TEST_PATHS)[0]
            if view == "side"
            else None
        )
        arrays = {"cycles": cyc, **{f"region_{k}": v for k, v in regs.items()}}
        if ref is not None:
            arrays["reference"] = ref
        np.savez(os.path.join(directory, f"{view}.npz"), **arrays)
        print(f"cycles_addon_saved: {view} saved in {directory}")


def load(directory, lighting):
    """Outside Blender: the fast march against the saved renders."""
    import welkin

    def luminance(x):
        return np.asarray(x)[..., :3] @ LUMINANCE

    def fast(view, extra):
        with open(os.path.join(directory, f"scene_{view}.json")) as f:
            desc = json.load(f)
        desc["clouds"].setdefault("lighting", {}).update({**lighting, **extra})
        scene = welkin.SceneDescription.from_json_string(json.dumps(desc))
        return np.asarray(welkin.cloud_passes(scene)["Welkin.Clouds"])

    side = np.load(os.path.join(directory, "side.npz"))
    regs = {k[len("region_") :]: side[k] for k in side.files if k.startswith("region_")}
    cyc, ref = luminance(side["cycles"]), luminance(side["reference"])
    full, single = luminance(fast("side", {})), luminance(fast("side", {"octaves": 1}))
    print(
        "side view, per region: fast / Cycles, fast / reference; over the reference: single + sky, the rest"
    )
    for k in ("all", "sunlit", "shadow", "base", "edge", "core"):
        m = regs[k]
        r = ref[m].sum()
        print(
            f"  {k:7s} {full[m].sum() / cyc[m].sum():.3f}  {full[m].sum() / r:.3f}   "
            f"{single[m].sum() / r:.3f}  {(full - single)[m].sum() / r:.3f}"
        )
    back = np.load(os.path.join(directory, "backlit.npz"))
    regs = {k[len("region_") :]: back[k] for k in back.files if k.startswith("region_")}
    x = fast("backlit", {})

    def edge_over_core(img):  # as bench/cycles_addon_clouds.py's edge_over_core
        a = luminance(img) / np.maximum(img[..., 3], 1e-6)
        return float(a[regs["edge"]].mean() / a[regs["core"]].mean())

    lc, lw = edge_over_core(back["cycles"]), edge_over_core(x)
    print(f"backlit: edge over core: Cycles {lc:.3f}, fast {lw:.3f} ({lw / lc:.3f} of Cycles')")


def main():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    p = argparse.ArgumentParser()
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--save", metavar="DIR", help="in Blender 5.0: render and keep Cycles and the reference")
    g.add_argument("--load", metavar="DIR", help="outside Blender: the fast march against DIR's renders")
    p.add_argument("--lighting", default="{}", help="JSON merged into the scene's clouds.lighting")
    args = p.parse_args(argv)
    if args.save:
        save(args.save)
    else:
        load(args.load, json.loads(args.lighting))


main()
