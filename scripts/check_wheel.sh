#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Checks each repaired wheel (scripts/build_wheel.sh) as a Python user outside Blender gets
# it: `pip install` into a fresh virtual environment of the wheel's own Python (cp311: 3.11,
# cp313: 3.13, found by scripts/find_python.sh), not the one the module in build/ was built
# for, then
#   * `import welkin` from that venv alone (no PYTHONPATH), the README's calls
#     welkin.Atmosphere.preset(...) and welkin.sky_radiance(...) give the same radiance as
#     the module built by scripts/build.sh (/usr/bin/python3, PYTHONPATH=build), and the
#     module's public names are the same;
#   * `ldd` of the installed module resolves every library, and each one is either inside
#     the wheel (welkin.libs/) or on the list its manylinux tag lets a wheel take from the
#     system (auditwheel's policy: glibc's libraries, libstdc++, libgcc_s, libz...): nothing
#     from Debian's OpenVDB, TBB, OpenEXR, Imath, blosc, boost, fmt...
#
#   bash scripts/check_wheel.sh WHEEL [WHEEL ...]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/find_python.sh

probe='
import json, sys
import numpy as np
import welkin
atm = welkin.Atmosphere.preset("bruneton2017")
dirs = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.05], [0.3, -0.5, 0.8]])
sun = np.array([0.5, 0.2, 0.6])
L = welkin.sky_radiance(atm, 0.0, sun, dirs, output="rgb")
sky = welkin.sky_image(atm, 0.0, sun / np.linalg.norm(sun), 64)  # the HDRI, 64 x 32
print(json.dumps({"file": welkin.__file__, "python": sys.version.split()[0],
                  "L": np.asarray(L).tolist(), "sky": np.asarray(sky).tolist(),
                  "names": sorted(n for n in dir(welkin) if not n.startswith("_"))}))
'
check() {
local wheel python tag_py venv venv_python wheel_out build_out tag allowed
wheel=$(realpath "$1")
tag_py=$(basename "$wheel" | sed -n 's/^welkin-[^-]*-cp3\([0-9]*\)-.*/3.\1/p')
[[ -n $tag_py ]] || { echo "check_wheel: $wheel: no cp3XY tag in its name" >&2; return 1; }
python=$(welkin_find_python "$tag_py")
venv=build/venv-wheel-check-$tag_py
rm -rf "$venv"
"$python" -m venv "$venv"
"$venv/bin/python" -m pip install -q --disable-pip-version-check "$wheel"
# From /tmp, so that nothing of the repository is importable.
venv_python=$(pwd)/$venv/bin/python
wheel_out=$(cd /tmp && env -u PYTHONPATH "$venv_python" -c "$probe")
build_out=$(PYTHONPATH="$(pwd)/build" /usr/bin/python3 -c "$probe")

# The libraries the wheel's manylinux tag lets it take from the system: auditwheel's own
# policy (build/venv-wheel-tools, scripts/build_wheel.sh).
tag=$(basename "$wheel" | sed -n 's/.*-\(manylinux_[0-9]*_[0-9]*\)_x86_64\.whl$/\1/p')
allowed=$(build/venv-wheel-tools/bin/python -c "
import json, pathlib, auditwheel
policy = next(pathlib.Path(auditwheel.__file__).parent.rglob('manylinux-policy.json'))
print(' '.join(next(p for p in json.loads(policy.read_text()) if p['name'] == '$tag')['lib_whitelist']))")

/usr/bin/python3 - "$wheel_out" "$build_out" "$(pwd)/$venv" "$tag" "$allowed" <<'PY'
import json, subprocess, sys
import numpy as np
wheel, build, venv = json.loads(sys.argv[1]), json.loads(sys.argv[2]), sys.argv[3]
tag, allowed = sys.argv[4], tuple(sys.argv[5].split())
assert wheel["file"].startswith(venv), f"`import welkin` found {wheel['file']}, not the venv's"
assert wheel["names"] == build["names"], (
    f"the wheel's API differs: {set(wheel['names']) ^ set(build['names'])}")
a, b = np.array(wheel["L"]), np.array(build["L"])
assert np.isfinite(a).all() and (a > 0).all(), a
assert np.allclose(a, b, rtol=1e-5, atol=0), f"wheel {a} vs build {b}"
sa, sb = np.array(wheel["sky"]), np.array(build["sky"])
assert sa.shape == sb.shape == (32, 64, 3), (sa.shape, sb.shape)
assert np.isfinite(sa).all() and (sa >= 0).all() and sb.max() > 0
assert np.allclose(sa, sb, rtol=1e-5, atol=1e-7 * sb.max()), (
    f"wheel's sky_image differs from build/'s: max abs diff {np.abs(sa - sb).max():.3g}")
print(f"check_wheel: {wheel['file']} (Python {wheel['python']}): welkin.sky_radiance and "
      f"welkin.sky_image (64 x 32) match build/'s module (Python {build['python']}; max rel "
      f"diff {np.max(np.abs(a - b) / b):.1e}, sky max abs diff {np.abs(sa - sb).max():.1e}); "
      f"{len(wheel['names'])} public names, same")

assert allowed, f"no auditwheel policy for {tag!r}"
out = subprocess.run(["ldd", wheel["file"]], capture_output=True, text=True, check=True).stdout
bad, bundled = [], 0
for line in out.splitlines():
    line = line.strip()
    name = line.split()[0]
    if "not found" in line:
        bad.append(line)
    elif "=>" in line and "/welkin.libs/" in line.split("=>")[1]:
        bundled += 1
    elif name not in allowed and not name.startswith(("linux-vdso.so", "/lib64/ld-linux")):
        bad.append(line)
assert not bad, "libraries from outside the wheel:\n" + "\n".join(bad)
print(f"check_wheel: ldd: {bundled} libraries from the wheel's welkin.libs/, the rest on "
      f"{tag}'s list of system libraries")
PY
rm -rf "$venv"
}

(($#)) || { echo "usage: bash scripts/check_wheel.sh WHEEL [WHEEL ...]" >&2; exit 2; }
for w in "$@"; do
  check "$w"
done
