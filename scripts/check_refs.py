# SPDX-License-Identifier: Apache-2.0
"""Checks that what the code and the docs point at exists.

Run by scripts/lint.sh. It reads every tracked source, script and Markdown file and
reports, one line each, ``file:line: message``:

- a path of the repository (``src/sky/lut.cpp``, ``include/welkin/sky/method.hpp``,
  ``docs/design.md#layout``) or a source file's bare name (``lut.hpp``, ``farm.py``) that
  names no tracked file, or a Markdown anchor that names no heading of that file;
- a Markdown link whose target or anchor does not exist, or a section named by its heading
  in quotes after its file (README or a docs/ page) that is not there;
- a history reference in code: ``issue #N`` (the tracker is not in the repository: what a
  change did belongs in the git log) or a name of a file that lives outside it
  (a shared folder beside the checkout, a design file that moved into docs/).

A bare name resolves when some tracked file has that name; a path resolves relative to the
repository root, the naming file's folder, ``include/welkin/`` or ``src/``. Names of files
that programs write or read at run time (``sky.exr``, ``frame.json``) are not checked: only
the extensions of the repository's own sources are. Exits 1 when anything is reported.

    python3 scripts/check_refs.py [--list]    (--list: every resolved reference too)
"""

from __future__ import annotations

import re
import subprocess
import sys
import unicodedata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# The files read, by suffix, and the extensions whose bare names count as references.
READ_SUFFIXES = {".hpp", ".cpp", ".py", ".pyi", ".sh", ".md", ".toml", ".txt", ".ini", ".cmake", ".json"}
SOURCE_EXTENSIONS = ("hpp", "cpp", "py", "pyi", "sh", "md", "cmake", "sbatch")
TOP_FOLDERS = (
    "src",
    "include",
    "addon",
    "tests",
    "docs",
    "bench",
    "scripts",
    "blend",
    "cmake",
    "farm",
    ".ci",
)

PATH_RE = re.compile(
    r"(?<![\w./\-<\\$])((?:\.\./)*(?:[\w\-]+/)*[\w\-]+\.(?:" + "|".join(SOURCE_EXTENSIONS) + r"))"
    r"(#[\w\-]+)?(?![\w\-/])"
)
SLASHED_RE = re.compile(
    r"(?<![\w./\-<\\])((?:"
    + "|".join(re.escape(t) for t in TOP_FOLDERS)
    + r")/[\w./\-]*[\w\-])(#[\w\-]+)?(?![\w*{<$])"
)
MD_LINK_RE = re.compile(r"\]\(([^)\s]+)\)")
ISSUE_RE = re.compile(r"\bissue #\d+|(?:^|(?<=[\s(]))#\d+\b(?=[:)])", re.IGNORECASE)
OUTSIDE_RE = re.compile(r"\.\./shared/|\bDESIGN\.md\b")
FENCE_RE = re.compile(r"^\s*```")
# A section named by its heading in quotes after a Markdown file or README.
SECTION_RE = re.compile(r"\b((?:[\w\-]+/)*[\w\-]+\.md|README)(?:'s)? \"([^\"]+)\"")
PLACEHOLDER_RE = re.compile(r"(^|/)[A-Z][A-Z_]+(/|$)")

# Names that are rightly not in the repository, and why.
ELSEWHERE = {
    "FindOpenVDB.cmake": "OpenVDB's CMake module, installed by libopenvdb-dev",
    "blender_ext.py": "Blender's extension tool, inside each Blender",
    "session.cpp": "a source file of Cycles",
    "bench/results/quick": "the folder bench/chart.py --quick writes",
    "tests/fuzz/openvdb_findings": "the folder scripts/fuzz.sh writes its findings to",
    "welkin_native.pyi": "the module's stub as scripts/stub_protocol.py writes it for mypy",
    "welkin_native_protocol.pyi": "the Protocol scripts/stub_protocol.py writes for mypy",
}


def tracked() -> list[str]:
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, check=True, capture_output=True)
    return [p for p in out.stdout.decode().split("\0") if p]


def slug(heading: str) -> str:
    """GitHub's anchor for a Markdown heading: lower case, punctuation dropped, spaces to -."""
    text = unicodedata.normalize("NFKC", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


class Repo:
    """The tracked files, their folders, their bare names and the Markdown headings."""

    def __init__(self, files: list[str]) -> None:
        self.files = set(files)
        self.dirs = {str(p) for f in files for p in Path(f).parents if str(p) != "."}
        self.names: dict[str, list[str]] = {}
        for f in files:
            self.names.setdefault(Path(f).name, []).append(f)
        self._anchors: dict[str, set[str]] = {}

    def anchors(self, md: str) -> set[str]:
        if md not in self._anchors:
            found: set[str] = set()
            in_fence = False
            for line in (ROOT / md).read_text(encoding="utf-8").splitlines():
                if FENCE_RE.match(line):
                    in_fence = not in_fence
                elif not in_fence and line.startswith("#"):
                    base = slug(line.lstrip("#"))
                    n, anchor = 1, base
                    while anchor in found:  # GitHub numbers repeated headings
                        anchor, n = f"{base}-{n}", n + 1
                    found.add(anchor)
            self._anchors[md] = found
        return self._anchors[md]

    def resolve(self, name: str, where: str) -> str | None:
        """The tracked file or folder that `name`, written in file `where`, names."""
        name = name.rstrip("/")
        candidates = [
            name,
            str(Path(where).parent / name),
            f"include/{name}",
            f"include/welkin/{name}",
            f"src/{name}",
            f"addon/welkin/{name}",
        ]
        stem, dot, _ = name.rpartition(".")
        if dot and "/" in stem:  # a Python module's symbol: package/module.function
            candidates.append(stem + ".py")
        for c in candidates:
            norm = str(Path(c)).replace("\\", "/")
            parts: list[str] = []
            for part in norm.split("/"):
                if part == "..":
                    if not parts:
                        break
                    parts.pop()
                elif part != ".":
                    parts.append(part)
            else:
                path = "/".join(parts)
                if path in self.files or path in self.dirs:
                    return path
        if "/" not in name and name in self.names:
            return self.names[name][0]
        return None


def check_target(repo: Repo, target: str, anchor: str | None, where: str) -> str | None:
    """None if `target` (with `anchor`) exists, else what is wrong."""
    if target in ELSEWHERE or PLACEHOLDER_RE.search(target):
        return None
    path = repo.resolve(target, where) if target else where
    if path is None:
        return f"names {target}, which is not in the repository"
    if anchor and path.endswith(".md") and anchor.lstrip("#") not in repo.anchors(path):
        return f"names {target}{anchor}: {path} has no such heading"
    return None


def scan(repo: Repo, path: str) -> list[str]:
    problems: list[str] = []
    is_md = path.endswith(".md")
    is_code = not is_md
    in_fence = False
    text = (ROOT / path).read_text(encoding="utf-8", errors="replace")
    for number, line in enumerate(text.splitlines(), 1):
        if is_md and FENCE_RE.match(line):
            in_fence = not in_fence
        if line.lstrip().startswith("#include"):
            continue  # the compiler checks includes
        seen: set[str] = set()
        if is_md and not in_fence:
            for link in MD_LINK_RE.findall(line):
                if re.match(r"[a-z]+:", link) or link.startswith("mailto"):
                    continue
                target, _, anchor = link.partition("#")
                seen.add(target)
                msg = check_target(repo, target, "#" + anchor if anchor else None, path)
                if msg:
                    problems.append(f"{path}:{number}: link {msg}")
        for regex in (SLASHED_RE, PATH_RE):
            for m in regex.finditer(line):
                target, anchor = m.group(1), m.group(2)
                if target in seen or "*" in target or "<" in target:
                    continue
                seen.add(target)
                if regex is PATH_RE and "/" not in target and target.split(".")[-1] not in SOURCE_EXTENSIONS:
                    continue
                if is_code and "/" not in target and re.search(rf"[\"']{re.escape(target)}[\"']", line):
                    continue  # a file the code makes or names at run time ("bad.py")
                msg = check_target(repo, target, anchor, path)
                if msg:
                    problems.append(f"{path}:{number}: {msg}")
        for m in SECTION_RE.finditer(line):
            md = m.group(1) if m.group(1).endswith(".md") else "README.md"
            msg = check_target(repo, md, "#" + slug(m.group(2)), path)
            if msg:
                problems.append(f'{path}:{number}: section "{m.group(2)}": {msg}')
        if is_code and ISSUE_RE.search(line):
            problems.append(
                f"{path}:{number}: cites '{ISSUE_RE.search(line).group(0)}' of a tracker "
                "outside the repository (history belongs in the git log)"
            )
        if OUTSIDE_RE.search(line) and path != "scripts/check_refs.py":
            problems.append(
                f"{path}:{number}: names a file outside the repository ({OUTSIDE_RE.search(line).group(0)})"
            )
    return problems


def main() -> int:
    files = tracked()
    repo = Repo(files)
    problems: list[str] = []
    for f in sorted(files):
        p = Path(f)
        if p.suffix in READ_SUFFIXES and not f.startswith("tests/data/") and (ROOT / f).is_file():
            problems.extend(scan(repo, f))
    for line in problems:
        print(line)
    if problems:
        print(f"check_refs: {len(problems)} reference(s) that lead nowhere", file=sys.stderr)
        return 1
    print(f"check_refs: every reference resolves ({len(files)} files)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
