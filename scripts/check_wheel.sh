#!/usr/bin/env bash
# Checks the repaired wheel (scripts/build_wheel.sh) as a Python user outside Blender gets
# it: `pip install` into a fresh virtual environment of a Python 3.11 that is not the one
# the module in build/ was built for, then
#   * `import welkin` from that venv alone (no PYTHONPATH), the README's calls
#     welkin.Atmosphere.preset(...) and welkin.sky_radiance(...) give the same radiance as
#     the module built by scripts/build.sh (/usr/bin/python3, PYTHONPATH=build), and the
#     module's public names are the same;
#   * `ldd` of the installed module resolves every library, and each one is either inside
#     the wheel (welkin.libs/) or one the manylinux policy lets a wheel take from the system
#     (glibc's libraries, libstdc++, libgcc_s): nothing from Debian's OpenVDB, TBB,
#     OpenEXR, Imath, blosc, boost, fmt...
#
#   bash scripts/check_wheel.sh WHEEL    ($WELKIN_CHECK_PYTHON: the venv's Python 3.11)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

wheel=$(realpath "$1")
python=${WELKIN_CHECK_PYTHON:-python3}
venv=build/venv-wheel-check
rm -rf "$venv"
"$python" -m venv "$venv"
"$venv/bin/python" -m pip install -q --disable-pip-version-check "$wheel"

probe='
import json, sys
import numpy as np
import welkin
atm = welkin.Atmosphere.preset("bruneton2017")
dirs = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.05], [0.3, -0.5, 0.8]])
sun = np.array([0.5, 0.2, 0.6])
L = welkin.sky_radiance(atm, 0.0, sun, dirs, output="rgb")
print(json.dumps({"file": welkin.__file__, "L": np.asarray(L).tolist(),
                  "names": sorted(n for n in dir(welkin) if not n.startswith("_"))}))
'
# From /tmp, so that nothing of the repository is importable.
venv_python=$(pwd)/$venv/bin/python
wheel_out=$(cd /tmp && env -u PYTHONPATH "$venv_python" -c "$probe")
build_out=$(PYTHONPATH="$(pwd)/build" /usr/bin/python3 -c "$probe")

/usr/bin/python3 - "$wheel_out" "$build_out" "$(pwd)/$venv" <<'PY'
import json, subprocess, sys
import numpy as np
wheel, build, venv = json.loads(sys.argv[1]), json.loads(sys.argv[2]), sys.argv[3]
assert wheel["file"].startswith(venv), f"`import welkin` found {wheel['file']}, not the venv's"
assert wheel["names"] == build["names"], (
    f"the wheel's API differs: {set(wheel['names']) ^ set(build['names'])}")
a, b = np.array(wheel["L"]), np.array(build["L"])
assert np.isfinite(a).all() and (a > 0).all(), a
assert np.allclose(a, b, rtol=1e-5, atol=0), f"wheel {a} vs build {b}"
print(f"check_wheel: {wheel['file']}: welkin.sky_radiance matches build/'s module "
      f"(max rel diff {np.max(np.abs(a - b) / b):.1e}); {len(wheel['names'])} public names, same")

# manylinux: the libraries a wheel may take from the system (glibc's, libstdc++, libgcc_s).
allowed = ("linux-vdso.so", "ld-linux-x86-64.so", "libc.so", "libm.so", "libpthread.so",
           "libdl.so", "librt.so", "libstdc++.so", "libgcc_s.so", "libutil.so")
out = subprocess.run(["ldd", wheel["file"]], capture_output=True, text=True, check=True).stdout
bad, bundled = [], 0
for line in out.splitlines():
    line = line.strip()
    name = line.split()[0]
    if "not found" in line:
        bad.append(line)
    elif "=>" in line and "/welkin.libs/" in line.split("=>")[1]:
        bundled += 1
    elif not name.startswith(allowed) and not name.startswith("/lib64/ld-linux"):
        bad.append(line)
assert not bad, "libraries from outside the wheel:\n" + "\n".join(bad)
print(f"check_wheel: ldd: {bundled} libraries from the wheel's welkin.libs/, the rest glibc's "
      "and the C++ runtime's")
PY
rm -rf "$venv"
