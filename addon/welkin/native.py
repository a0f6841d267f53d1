# SPDX-License-Identifier: GPL-3.0-or-later
"""Finding and loading Welkin's compiled module, shipped inside the add-on.

The add-on zip carries the module built by scripts/build.sh in `_native/`
(welkin.cpython-311-x86_64-linux-gnu.so for Blender 3.4's Python 3.11). The add-on package
is itself called `welkin`, so the compiled module is imported under the dotted name
`<package>._native.welkin` (its init function, PyInit_welkin, is found from the last part
of that name); a top-level `welkin` elsewhere on sys.path is never picked up by mistake.

As a Blender Extension (4.2+) there is no `_native/`: the compiled module comes as the wheel
(scripts/build_wheel.sh) that Blender installs into the extensions' site-packages (the
Extension carries one for Python 3.11, Blender 4.2-5.0, and one for 3.13, Blender 5.1 and
later; Blender installs the one of its Python), a
top-level extension module file `welkin<suffix>`. It is found by that file name on
sys.path, never by `import welkin` (which may give this add-on: Blender 3.x puts the
add-ons folder on sys.path, where this package is `welkin`). It is loaded as `welkin` when
that name is free, so that scripts doing `import welkin` share the one instance (a pybind11
module initialised twice in one process fails), else under the private dotted name above.
The add-on's own package (`welkin` or `bl_ext.<repo>.welkin`) forwards the module's names
(its __getattr__), so `import welkin; welkin.Atmosphere.preset(...)` works in whichever
order the two are found.

Loading never raises: `load()` returns the module, or None and a message that says what is
wrong and how to fix it (missing, built for another Python, failing to load), for the
panel and for operator reports.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import pathlib
import sys
import types
from typing import TYPE_CHECKING, cast

NATIVE_DIR = pathlib.Path(__file__).resolve().parent / "_native"
BUILD_HINT = (
    "Welkin needs Blender 3.4 or later on x86-64 Linux, with Python 3.11 "
    "(Blender 3.4-5.0) or 3.13 (5.1 and later): for Blender 4.2 and later install "
    "the Extension (welkin-<version>-linux_x64.zip, scripts/build_extension.sh; "
    "it carries the module for both), for 3.4-4.1 the add-on zip "
    "(scripts/build_addon.sh, Python 3.11)"
)

if TYPE_CHECKING:
    # The compiled module's stub (src/python/welkin.pyi) under a name that is not the
    # add-on's, and its API as a Protocol, both written by scripts/stub_protocol.py onto
    # mypy's path (mypy.ini): the module object loaded here is typed as that Protocol, so
    # mypy checks every call the add-on makes into it against the stub; the stub's module
    # must itself satisfy the Protocol.
    import welkin_native
    from welkin_native_protocol import Module

    _conforms: Module = welkin_native

_cache: dict[str, tuple[Module | None, str | None]] = {}


def _python_tag() -> str:
    return f"Python {sys.version_info.major}.{sys.version_info.minor}"


def installed() -> pathlib.Path | None:
    """The module file of an installed welkin wheel on sys.path for this Python, or None."""
    for entry in sys.path:
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = pathlib.Path(entry or ".") / ("welkin" + suffix)
            if path.is_file():
                return path.resolve()
    return None


def _installed_elsewhere() -> list[str]:
    """Names of welkin module files on sys.path built for another Python."""
    names: set[str] = set()
    for entry in sys.path:
        try:
            names.update(
                p.name
                for p in pathlib.Path(entry or ".").glob("welkin.*")
                if p.suffix in (".so", ".pyd") and p.is_file()
            )
        except OSError:
            pass
    return sorted(names)


def find(directory: str | pathlib.Path = NATIVE_DIR) -> tuple[pathlib.Path | None, str | None]:
    """(path of a loadable module file or None, message or None)."""
    directory = pathlib.Path(directory)
    candidates = sorted(p for p in directory.glob("welkin*") if p.suffix in (".so", ".pyd"))
    if not candidates and directory == NATIVE_DIR:
        path = installed()
        if path is not None:
            return path, None
        candidates = [pathlib.Path(n) for n in _installed_elsewhere()]
    if not candidates:
        where = (
            f"nothing in {directory}, nor the Extension's wheel on sys.path"
            if directory == NATIVE_DIR
            else f"nothing in {directory}"
        )
        return None, f"Welkin's compiled module is missing ({where}); " + BUILD_HINT
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        for path in candidates:
            if path.name == "welkin" + suffix:
                return path, None
    names = ", ".join(p.name for p in candidates)
    return None, (
        f"Welkin's compiled module ({names}) was built for another Python: this "
        f"Blender runs {_python_tag()} and loads welkin"
        f"{importlib.machinery.EXTENSION_SUFFIXES[0]}; " + BUILD_HINT
    )


def load(
    directory: str | pathlib.Path = NATIVE_DIR, package: str | None = None
) -> tuple[Module | None, str | None]:
    """(module or None, message or None). Cached per directory."""
    directory = pathlib.Path(directory)
    key = str(directory)
    if key in _cache:
        return _cache[key]
    path, message = find(directory)
    module: types.ModuleType | None = None
    if path is not None:
        name = f"{package or __package__ or 'welkin_addon'}._native.welkin"
        if path.parent != directory:  # the installed wheel's module
            current = sys.modules.get("welkin")
            if current is None or pathlib.Path(getattr(current, "__file__", "") or "") == path:
                name = "welkin"
        try:
            module = sys.modules.get(name)
            if module is None:
                spec = importlib.util.spec_from_file_location(name, path)
                if spec is None or spec.loader is None:
                    raise ImportError(f"no loader for {path}")
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                sys.modules[name] = module
        except (ImportError, OSError) as error:
            module = None
            message = (
                f"Welkin's compiled module {path.name} could not be loaded in "
                f"{_python_tag()}: {error}; " + BUILD_HINT
            )
    # The one unchecked step: the file loaded is the module the stub describes (lint
    # checks the stub against the built module).
    _cache[key] = (cast("Module | None", module), message)
    return _cache[key]


def module() -> Module | None:
    """The compiled module shipped with this add-on, or None (see message())."""
    return load()[0]


def message() -> str | None:
    """Why the compiled module is unavailable, or None when it loaded."""
    return load()[1]
