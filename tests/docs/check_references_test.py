#!/usr/bin/python3
"""check_references.py on a small tree of its own: every kind of broken reference is
reported (with its file and line) and the same tree, repaired, passes.

Usage: check_references_test.py PATH_TO_check_references.py
"""

import os
import subprocess
import sys
import tempfile

BROKEN = {
    "docs/GUIDE.md": """# Guide

## 1. One

1. the first step

Good: `src/part.h`, `docs/GUIDE.md` §1, `docs/GUIDE.md` §1, step 1, `src/part.h:Known`.
Bad path: `src/gone.h`.
Bad section: `docs/GUIDE.md` §2.
Bad step: `docs/GUIDE.md` §1, step 3.
Bad symbol: `src/part.h:Unknown`.
Moved library header: `lib/thing.h`.
""",
    "src/part.h": """#pragma once
// What it is: see docs/GONE.md and the board's part.cc.
int Known = 0;
""",
    "src/part.cc": """#include "part.h"
#if defined(__arm__)
#endif
""",
    "docs/CONVENTIONS.md": """# Conventions

- Host-or-target choices: only `src/part.h` tests `defined(__arm__)`.
""",
}

EXPECTED = [
    "docs/GUIDE.md:8: 'src/gone.h'",
    "docs/GUIDE.md:9: docs/GUIDE.md has no section 2",
    "docs/GUIDE.md:10: docs/GUIDE.md §1 has no step 3",
    "docs/GUIDE.md:11: 'src/part.h:Unknown': src/part.h has no Unknown",
    "docs/GUIDE.md:12: 'lib/thing.h'",
    "src/part.h:2: 'docs/GONE.md'",
    "src/part.cc: tests __arm__",
]

REPAIRS = {
    "docs/GUIDE.md": [("`src/gone.h`", "`src/part.h`"), ("§2.", "§1."),
                      ("step 3", "step 1"), ("part.h:Unknown", "part.h:Known"),
                      ("`lib/thing.h`", "`src/part.cc`")],
    "src/part.h": [("docs/GONE.md", "docs/GUIDE.md")],
    "docs/CONVENTIONS.md": [("only `src/part.h` tests", "only `src/part.cc` tests")],
}


def write_tree(root, files):
    for path, text in files.items():
        full = os.path.join(root, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "w", encoding="utf-8") as fh:
            fh.write(text)
    subprocess.run(["git", "-C", root, "add", "-A"], check=True)


def run(checker, root):
    result = subprocess.run([sys.executable, checker, root], capture_output=True, text=True)
    return result.returncode, result.stdout


def main():
    checker = os.path.abspath(sys.argv[1])
    failures = []
    with tempfile.TemporaryDirectory() as root:
        subprocess.run(["git", "init", "-q", root], check=True)
        write_tree(root, BROKEN)
        status, out = run(checker, root)
        if status != 1:
            failures.append(f"broken tree: exit {status}, expected 1\n{out}")
        lines = out.splitlines()
        for expected in EXPECTED:
            if not any(line.startswith(expected) for line in lines):
                failures.append(f"broken tree: no report starting with {expected!r}\n{out}")
        unresolved = [l for l in lines if not l.startswith("references checked")]
        if len(unresolved) != len(EXPECTED):
            failures.append(f"broken tree: {len(unresolved)} reports, expected "
                            f"{len(EXPECTED)}\n{out}")

        repaired = dict(BROKEN)
        for path, edits in REPAIRS.items():
            for old, new in edits:
                assert old in repaired[path], (path, old)
                repaired[path] = repaired[path].replace(old, new)
        write_tree(root, repaired)
        status, out = run(checker, root)
        if status != 0 or "unresolved: 0" not in out:
            failures.append(f"repaired tree: exit {status}, expected 0\n{out}")

    for f in failures:
        print("FAIL:", f)
    print(f"{len(EXPECTED) + 1 - len(failures) if not failures else 0} passed, "
          f"{len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
