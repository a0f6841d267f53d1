"""Finding and loading Welkin's compiled module, shipped inside the add-on.

The add-on zip carries the module built by scripts/build.sh in `_native/`
(welkin.cpython-311-x86_64-linux-gnu.so for Blender 3.4's Python 3.11). The add-on package
is itself called `welkin`, so the compiled module is imported under the dotted name
`<package>._native.welkin` (its init function, PyInit_welkin, is found from the last part
of that name); a top-level `welkin` elsewhere on sys.path is never picked up by mistake.

Loading never raises: `load()` returns the module, or None and a message that says what is
wrong and how to fix it (missing, built for another Python, failing to load), for the
panel and for operator reports.
"""
import importlib.machinery
import importlib.util
import pathlib
import sys

NATIVE_DIR = pathlib.Path(__file__).resolve().parent / "_native"
BUILD_HINT = ("build the add-on zip with `bash scripts/build_addon.sh` (it builds the module "
              "for /usr/bin/python3) and install that zip")

_cache = {}


def _python_tag():
    return f"Python {sys.version_info.major}.{sys.version_info.minor}"


def find(directory=NATIVE_DIR):
    """(path of a loadable module file or None, message or None)."""
    directory = pathlib.Path(directory)
    candidates = sorted(p for p in directory.glob("welkin*") if p.suffix in (".so", ".pyd"))
    if not candidates:
        return None, (f"Welkin's compiled module is missing (nothing in {directory}); "
                      + BUILD_HINT)
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        for path in candidates:
            if path.name == "welkin" + suffix:
                return path, None
    names = ", ".join(p.name for p in candidates)
    return None, (f"Welkin's compiled module ({names}) was built for another Python: this "
                  f"Blender runs {_python_tag()} and loads welkin"
                  f"{importlib.machinery.EXTENSION_SUFFIXES[0]}; " + BUILD_HINT)


def load(directory=NATIVE_DIR, package=None):
    """(module or None, message or None). Cached per directory."""
    directory = pathlib.Path(directory)
    key = str(directory)
    if key in _cache:
        return _cache[key]
    path, message = find(directory)
    module = None
    if path is not None:
        name = f"{package or __package__ or 'welkin_addon'}._native.welkin"
        try:
            module = sys.modules.get(name)
            if module is None:
                spec = importlib.util.spec_from_file_location(name, path)
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                sys.modules[name] = module
        except (ImportError, OSError) as error:
            module = None
            message = (f"Welkin's compiled module {path.name} could not be loaded in "
                       f"{_python_tag()}: {error}; " + BUILD_HINT)
    _cache[key] = (module, message)
    return module, message


def module():
    """The compiled module shipped with this add-on, or None (see message())."""
    return load()[0]


def message():
    """Why the compiled module is unavailable, or None when it loaded."""
    return load()[1]
