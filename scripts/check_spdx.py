# SPDX-License-Identifier: Apache-2.0
"""Checks that every source file states its licence in an SPDX line.

The add-on (addon/) is GPL-3.0-or-later, as Blender's Extensions platform requires; the
rest (the core, the module, the CLI, tests, benches, scripts) is Apache-2.0 (README.md,
"Licence"). Each tracked C++, Python, shell and CMake file carries
``SPDX-License-Identifier: <licence>`` in a comment within its first three lines (after a
shebang, if any). Run by scripts/lint.sh; ``--fix`` adds the line where it is missing.

    python3 scripts/check_spdx.py [--fix]
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COMMENT = {
    ".cpp": "//",
    ".hpp": "//",
    ".py": "#",
    ".pyi": "#",
    ".sh": "#",
    ".cmake": "#",
    ".sbatch": "#",
    "CMakeLists.txt": "#",
}
TAG = "SPDX-License-Identifier:"


def licence_of(path: str) -> str:
    return "GPL-3.0-or-later" if path.startswith("addon/") else "Apache-2.0"


def comment_of(path: str) -> str | None:
    p = Path(path)
    return COMMENT.get(p.name) or COMMENT.get(p.suffix)


def check(path: str, fix: bool) -> str | None:
    prefix = comment_of(path)
    if prefix is None or path.startswith("tests/data/"):
        return None
    file = ROOT / path
    lines = file.read_text(encoding="utf-8").splitlines(keepends=True)
    want = f"{TAG} {licence_of(path)}"
    head = lines[:3]
    if any(want in line for line in head):
        return None
    if any(TAG in line for line in head):
        return f"{path}: the SPDX line names another licence than {licence_of(path)}"
    if fix:
        at = 1 if lines and lines[0].startswith("#!") else 0
        lines.insert(at, f"{prefix} {want}\n")
        file.write_text("".join(lines), encoding="utf-8")
        return None
    return f"{path}: no '{want}' line in its first three lines"


def main() -> int:
    fix = "--fix" in sys.argv[1:]
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, check=True, capture_output=True)
    files = [p for p in out.stdout.decode().split("\0") if p and (ROOT / p).is_file()]
    problems = [msg for f in sorted(files) if (msg := check(f, fix))]
    for msg in problems:
        print(msg)
    if problems:
        print(
            f"check_spdx: {len(problems)} file(s) without their licence line "
            "(python3 scripts/check_spdx.py --fix adds them)",
            file=sys.stderr,
        )
        return 1
    print("check_spdx: every source file names its licence")
    return 0


if __name__ == "__main__":
    sys.exit(main())
