# SPDX-License-Identifier: Apache-2.0
"""Checks that functions stay short enough to do one thing.

A C++ function may be at most 120 lines long and a Python one at most 100 (lizard's
count, from its signature to its closing line). Longer ones are split into named steps;
the few that are better whole are listed in ALLOWED with the reason. Run by
scripts/lint.sh with the lint venv's lizard (pinned there).

    build/venv-lint/bin/python scripts/check_length.py
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import lizard

ROOT = Path(__file__).resolve().parent.parent
LIMITS = {".cpp": 120, ".hpp": 120, ".py": 100}

# (file, function name as lizard gives it): why it stays whole for now.
ALLOWED: dict[tuple[str, str], str] = {}


def main() -> int:
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, check=True, capture_output=True)
    files = [
        p
        for p in out.stdout.decode().split("\0")
        if Path(p).suffix in LIMITS and not p.startswith("tests/data/") and (ROOT / p).is_file()
    ]
    problems: list[str] = []
    for path in sorted(files):
        limit = LIMITS[Path(path).suffix]
        for fn in lizard.analyze_file(str(ROOT / path)).function_list:
            if fn.length > limit and (path, fn.name) not in ALLOWED:
                problems.append(f"{path}:{fn.start_line}: {fn.name} is {fn.length} lines (at most {limit})")
    for msg in problems:
        print(msg)
    if problems:
        print(
            f"check_length: {len(problems)} function(s) too long: split them into named steps",
            file=sys.stderr,
        )
        return 1
    print(f"check_length: every function within its limit ({len(files)} files)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
