# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures for the tests of the `welkin` Python module.

The module is the one built in build/ (scripts/test.sh sets PYTHONPATH=build); when
pytest runs without it, build/ is put on sys.path here so `python3 -m pytest
tests/python` works from a fresh build. Run with /usr/bin/python3, the Python the module
is built for.

The add-on's bpy-free modules (addon/welkin, without its blender/ subpackage) are loaded
here as the package `welkin_addon` (its name would clash with the compiled `welkin`), so
tests import them as `from welkin_addon import scene_export`.
"""

import importlib.util
import pathlib
import sys

import numpy as np
import pytest

_BUILD = pathlib.Path(__file__).resolve().parents[2] / "build"
if str(_BUILD) not in sys.path:
    sys.path.append(str(_BUILD))

import welkin  # noqa: E402

_ADDON = pathlib.Path(__file__).resolve().parents[2] / "addon" / "welkin"
if "welkin_addon" not in sys.modules:
    _spec = importlib.util.spec_from_file_location(
        "welkin_addon", _ADDON / "__init__.py", submodule_search_locations=[str(_ADDON)]
    )
    _package = importlib.util.module_from_spec(_spec)
    sys.modules["welkin_addon"] = _package
    _spec.loader.exec_module(_package)


@pytest.fixture
def atm():
    """A fresh Bruneton 2017 demo Earth at its own 680/550/440 nm (the tests' per-channel
    expectations; the library's default is 620/560/480/440 nm, tested in
    test_default_wavelengths.py and tests/cpp/test_default_colour.cpp)."""
    return welkin.Atmosphere.preset("bruneton2017", [680.0, 550.0, 440.0])


@pytest.fixture
def sun_direction():
    """Sun 30 degrees above the horizon, towards +Y."""
    e = np.radians(30.0)
    return (0.0, float(np.cos(e)), float(np.sin(e)))


@pytest.fixture
def view_directions():
    """(N, 3) C-contiguous float64 unit vectors covering the sphere, below the horizon too."""
    rng = np.random.default_rng(7)
    d = rng.normal(size=(24, 3))
    d[0] = (0.0, 0.0, 1.0)  # zenith
    d[1] = (1.0, 0.0, 0.0)  # horizon
    return d / np.linalg.norm(d, axis=1, keepdims=True)
