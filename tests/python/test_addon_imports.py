# SPDX-License-Identifier: Apache-2.0
"""Every import between the add-on's own modules names a module that exists.

The bpy layer (addon/welkin/blender/) cannot be imported outside Blender, so a module
moved or renamed without its importers would only fail once Blender loads it. This reads
every add-on file's `from .x import y` and `import` statements (and the Blender tests'
`from welkin.blender... import`) and resolves each against the files on disk: a relative
import, or an absolute one under the add-on's package name `welkin`, must name a module
(or a package with that submodule, or a name a module defines at its top level).
"""

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
ADDON = ROOT / "addon"  # the package `welkin` is addon/welkin


def _module_file(parts: list[str]) -> pathlib.Path | None:
    """The file of module welkin.<parts...> under addon/, or None."""
    base = ADDON.joinpath(*parts)
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _top_level_names(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
    return names


def _problems(path: pathlib.Path, package: list[str] | None) -> list[str]:
    """Unresolved imports of `path`; `package` is its package's parts under addon/ (None
    for a file outside the add-on, whose absolute `welkin.blender` imports are checked)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level and package is not None:
            base = package[: len(package) - (node.level - 1)]
            target = base + (node.module.split(".") if node.module else [])
        elif not node.level and node.module and node.module.split(".")[:2] == ["welkin", "blender"]:
            target = node.module.split(".")
        else:
            continue
        module = _module_file(target)
        where = f"{path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}:{node.lineno}"
        if module is None:
            out.append(f"{where}: no module {'.'.join(target)}")
            continue
        for alias in node.names:
            if _module_file(target + [alias.name]) is None and alias.name not in _top_level_names(module):
                out.append(f"{where}: {'.'.join(target)} has no {alias.name}")
    return out


def _files() -> list[tuple[pathlib.Path, list[str] | None]]:
    files = [(p, list(p.parent.relative_to(ADDON).parts)) for p in sorted((ADDON / "welkin").rglob("*.py"))]
    files += [(p, None) for p in sorted((ROOT / "tests" / "blender").glob("*.py"))]
    files += [(p, None) for p in sorted((ROOT / "bench").rglob("*.py"))]
    return files


@pytest.mark.parametrize(
    "path,package", _files(), ids=lambda v: str(v.relative_to(ROOT)) if isinstance(v, pathlib.Path) else ""
)
def test_addon_imports_resolve(path, package):
    assert _problems(path, package) == []


def test_the_checker_finds_a_missing_module(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("from welkin.blender import no_such_module\nfrom welkin.blender.sky import update\n")
    problems = _problems(bad, None)
    assert len(problems) == 1 and "no_such_module" in problems[0]
