#!/usr/bin/python3
"""Fails on any reference in the docs or the code's comments that does not resolve.

Usage: check_references.py REPO_ROOT [--list]

What it checks, in every tracked Markdown file and in the comments of every tracked
source, CMake, linker and shell file:

- a path in backticks (in Markdown) or written out in a comment, such as
  `firmware/core/FIXED_POINT.md` or hal/stm32g4/mmio.h: it names a tracked file or folder,
  from the repository's root, from the referring file's folder, or as an include path
  (the tail of a tracked file's path). A path with a `*` must match at least one tracked
  file. Not checked: output folders (`build/`, `out/`) and paths with variable parts
  (`<name>`, `$X`);
- a bare source file name (`flash.cc`, `stm32g474.ld`): some tracked file has that name;
- `file:Symbol` (`board.cc:BootEntry`): the file resolves and contains the symbol;
- `§N` after a reference to one of the repository's documents (`docs/DESIGN.md` §3,
  DESIGN §2): the document has a heading numbered N; `§N, step K`: that section has a
  numbered item K; `§N "Title"`: that section contains the title's words.

A reference to another project's tree (moteus's `fw/…`, ST's HAL `Src/…`) cannot be told
from a broken one of ours by its shape, so a line that names such a project is skipped;
the names are in EXTERNAL below. Exit status 1 lists every unresolved reference as
FILE:LINE: what; --list prints every reference checked.
"""

import os
import re
import subprocess
import sys

# Lines naming another project: their paths are that project's, not ours.
EXTERNAL = re.compile(
    r"moteus|mjbots|\bHAL\b|stm32g4xx|cmsis|CMSIS|X-CUBE|trezor|RIOT|zephyr|Zephyr|nuttx|"
    r"NuttX|Pigweed|modm|\bETL\b|ODrive|odrive|VESC|libopencm3|openocd|OpenOCD|Linux|"
    r"kernel's|linux/|/usr/|/dev/|/sys/|/proc/|/tmp/|/mnt|/etc/|https?://|python-can|"
    r"can-utils|canmatrix|Debian|stm32-cmake|embedded-hal|Bosch|ST's|QEMU hw/")

SOURCE_EXT = (".h", ".cc", ".c", ".ld", ".cmake", ".py", ".svd", ".sh")
PATH_EXT = SOURCE_EXT + (".md", ".json", ".txt", ".ini", ".dbc", ".yml", ".yaml")
GENERATED = ("build/", "out/", "./build", "./out")

TOKEN = re.compile(r"[A-Za-z0-9_.\-/*]+")
BACKTICK = re.compile(r"`([^`\n]+)`")
FILE_SYMBOL = re.compile(r"^([A-Za-z0-9_.\-/]+\.(?:h|cc|c|ld|cmake|py|sh|md)):([A-Za-z_][A-Za-z0-9_:~]*)$")
SECTION = re.compile(r"§\s*(\d+)(?:\s*[-–]\s*(\d+))?")


def tracked_files(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "-z"], check=True,
                         capture_output=True).stdout.decode()
    return [f for f in out.split("\0") if f and os.path.exists(os.path.join(root, f))]


class Tree:
    def __init__(self, root):
        self.root = root
        self.files = tracked_files(root)
        self.file_set = set(self.files)
        self.dirs = set()
        for f in self.files:
            parts = f.split("/")
            for i in range(1, len(parts)):
                self.dirs.add("/".join(parts[:i]))
        self.top = {f.split("/")[0] for f in self.files}
        # Files the build writes (configure_file and custom commands into the build tree).
        self.generated = set()
        for f in self.files:
            if f.endswith((".cmake", "CMakeLists.txt")):
                text = open(os.path.join(root, f), encoding="utf-8").read()
                self.generated.update(re.findall(r"BINARY_DIR\}/([A-Za-z0-9_./\-]+)", text))
        self.basenames = {}
        for f in self.files:
            self.basenames.setdefault(os.path.basename(f), []).append(f)

    def resolve(self, ref, referrer):
        """The tracked file or folder a path names, or None."""
        ref = ref.rstrip(".,;:)")
        bare = ref.rstrip("/")
        if not bare:
            return None
        here = os.path.dirname(referrer)
        candidates = [bare, os.path.normpath(os.path.join(here, bare))]
        for c in candidates:
            if c in self.file_set or c in self.dirs:
                return c
        if bare in self.generated:
            return bare
        if "*" in bare:
            pattern = re.compile("^(?:.*/)?" + re.escape(bare).replace(r"\*", "[^/]*") + "$")
            hits = [f for f in self.files if pattern.match(f)]
            return hits[0] if hits else None
        # A build product: a target that the named folder's CMakeLists.txt defines
        # (`tests/bench/sim_flood` is built as build/<preset>/tests/bench/sim_flood).
        folder, name = os.path.split(bare)
        folder = self.resolve(folder, referrer) if folder else None
        if folder and folder in self.dirs and "." not in name:
            lists = os.path.join(self.root, folder, "CMakeLists.txt")
            if os.path.exists(lists) and re.search(
                    r"\b" + re.escape(name) + r"\b", open(lists, encoding="utf-8").read()):
                return folder + "/" + name
        # A library's header named by the library's folder (firmware/protocol/messages.h
        # for firmware/protocol/include/mjc/protocol/messages.h), when it is the only one.
        if folder and folder in self.dirs:
            under = [f for f in self.files
                     if f.startswith(folder + "/") and os.path.basename(f) == name]
            if len(under) == 1:
                return under[0]
        # An include path, or a path given from inside its library.
        suffix = "/" + bare
        for f in self.files:
            if f.endswith(suffix):
                return f
        for d in self.dirs:
            if d.endswith(suffix):
                return d
        return None


def comment_text(path, line):
    """The comment part of a source line ('' when it has none)."""
    if path.endswith((".h", ".cc", ".c", ".ld")):
        i = line.find("//")
        if i >= 0:
            return line[i + 2:]
        s = line.strip()
        if s.startswith(("/*", "*")):
            return s.lstrip("/*")
        return ""
    if path.endswith((".cmake", ".sh", ".py")) or os.path.basename(path) in (
            "CMakeLists.txt",) or "/" not in path or path.startswith("scripts/"):
        i = line.find("#")
        if i >= 0 and not line[:i].rstrip().endswith("$"):
            return line[i + 1:]
    return ""


def is_markdown(path):
    return path.endswith(".md")


def checked_sources(tree):
    for f in tree.files:
        base = os.path.basename(f)
        if f.startswith("tests/fuzz/corpus/") or f.endswith(".svd") or f.startswith("tests/docs/"):
            continue
        if is_markdown(f) or f.endswith((".h", ".cc", ".c", ".ld", ".cmake", ".sh", ".py")) \
                or base == "CMakeLists.txt":
            yield f
            continue
        # Executable scripts without an extension (./run, ./test, scripts/*).
        full = os.path.join(tree.root, f)
        try:
            with open(full, "rb") as fh:
                if fh.read(2) == b"#!":
                    yield f
        except OSError:
            pass


def sections(text):
    """{N: (title, body)} for headings '## N. Title'."""
    out = {}
    current = None
    for line in text.splitlines():
        m = re.match(r"^#{1,4}\s+(\d+)\.?\s+(.*)$", line)
        if m:
            current = int(m.group(1))
            out[current] = [m.group(2), []]
            continue
        if re.match(r"^#{1,2}\s", line):
            current = None
        if current is not None:
            out[current][1].append(line)
    return {k: (v[0], "\n".join(v[1])) for k, v in out.items()}


def looks_like_path(tok, tree, in_backticks):
    if tok.startswith(("-", ".", "~")) and not tok.startswith("./"):
        return False
    if re.search(r"[<>{}$…]|\.\.\.", tok):
        return False
    t = tok.rstrip(".,;:)")
    if t.startswith("./"):
        t = t[2:]
    if not t or t.startswith(GENERATED):
        return False
    first = t.split("/")[0]
    if "/" in t:
        if first in tree.top or first in ("include",):
            return True
        # A path from inside a library (mjc/core/fixed.h, regs/flash.h, src/flash.cc).
        return t.endswith(PATH_EXT) and in_backticks or t.endswith(SOURCE_EXT)
    # A bare name; not a member access in a formula (k.h, step_.h).
    return t.endswith(SOURCE_EXT) and re.match(r"^[A-Za-z0-9][A-Za-z0-9_\-]{2,}(?<!_)\.[a-z]+$",
                                                t) is not None


def check_target_tests(tree):
    """docs/CONVENTIONS.md names every file that tests __arm__; any other one is a
    host-or-target choice outside the leaf header."""
    conventions = os.path.join(tree.root, "docs/CONVENTIONS.md")
    if not os.path.exists(conventions):
        return []
    text = open(conventions, encoding="utf-8").read()
    bullet = next((b for b in re.split(r"\n(?=- )", text) if "defined(__arm__)" in b), None)
    if bullet is None:
        return ["docs/CONVENTIONS.md: no bullet names the files that test __arm__"]
    named = {tree.resolve(r, "docs/CONVENTIONS.md") for r in BACKTICK.findall(bullet)}
    problems = []
    for f in tree.files:
        if not f.endswith((".h", ".cc", ".c")) or f.startswith("tests/"):
            continue
        with open(os.path.join(tree.root, f), encoding="utf-8", errors="replace") as fh:
            if re.search(r"defined\(__arm__\)", fh.read()) and f not in named:
                problems.append(f"{f}: tests __arm__ but docs/CONVENTIONS.md does not name it "
                                "among the files that may")
    return problems


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    root = os.path.abspath(sys.argv[1])
    listing = "--list" in sys.argv[2:]
    tree = Tree(root)
    doc_sections = {}
    problems = []
    counts = {"path": 0, "file:symbol": 0, "section": 0}

    def doc_for(name):
        path = tree.resolve(name, "")
        if path is None or not path.endswith(".md"):
            return None, None
        if path not in doc_sections:
            with open(os.path.join(root, path), encoding="utf-8") as fh:
                doc_sections[path] = sections(fh.read())
        return path, doc_sections[path]

    for f in checked_sources(tree):
        try:
            with open(os.path.join(root, f), encoding="utf-8") as fh:
                lines = fh.read().splitlines()
        except (UnicodeDecodeError, OSError):
            continue
        in_fence = False
        external_before = False
        for n, line in enumerate(lines, 1):
            if is_markdown(f):
                if line.lstrip().startswith("```"):
                    in_fence = not in_fence
                    continue
                if in_fence:
                    continue
                text = line
            else:
                text = comment_text(f, line)
            # A sentence that names another project may run on to the next line.
            continued = external_before and not re.match(r"^\s*([-*|#]|\d+\.)", text)
            external_before = bool(text) and (EXTERNAL.search(text) is not None or continued)
            if not text or external_before:
                continue
            where = f"{f}:{n}"

            refs = []  # (token, in_backticks)
            for m in BACKTICK.finditer(text):
                inner = m.group(1).strip()
                if " " not in inner:
                    refs.append((inner, True))
            if not is_markdown(f):
                stripped = BACKTICK.sub(" ", text)
                refs += [(t, False) for t in TOKEN.findall(stripped)]

            for tok, quoted in refs:
                fs = FILE_SYMBOL.match(tok)
                if fs:
                    counts["file:symbol"] += 1
                    path = tree.resolve(fs.group(1), f)
                    symbol = fs.group(2).split("::")[-1]
                    if listing:
                        print(f"{where}: {tok}")
                    if path is None or os.path.isdir(os.path.join(root, path)):
                        problems.append(f"{where}: '{tok}': no file {fs.group(1)}")
                        continue
                    with open(os.path.join(root, path), encoding="utf-8") as fh:
                        if not re.search(r"\b" + re.escape(symbol) + r"\b", fh.read()):
                            problems.append(f"{where}: '{tok}': {path} has no {symbol}")
                    continue
                if not looks_like_path(tok, tree, quoted):
                    continue
                counts["path"] += 1
                if listing:
                    print(f"{where}: {tok}")
                if tree.resolve(tok[2:] if tok.startswith("./") else tok, f) is None:
                    problems.append(f"{where}: '{tok}' names no file or folder of the tree")

            # § citations of our own documents.
            for m in SECTION.finditer(text):
                before = text[max(0, m.start() - 60):m.start()]
                docs = re.findall(r"([A-Za-z0-9_./\-]*\.md)`?\s*$", before)
                name = docs[-1] if docs else None
                if name is None and re.search(r"\b(DESIGN|[Dd]esign)\b\W*$", before):
                    name = "docs/DESIGN.md"
                if name is None:
                    continue  # another document's section (RM0440, the ARM ARM, ...)
                path, secs = doc_for(name)
                counts["section"] += 1
                if listing:
                    print(f"{where}: {name} §{m.group(1)}")
                if path is None:
                    problems.append(f"{where}: §{m.group(1)} of '{name}': no such document")
                    continue
                lo = int(m.group(1))
                hi = int(m.group(2)) if m.group(2) else lo
                for s in range(lo, hi + 1):
                    if s not in secs:
                        problems.append(f"{where}: {path} has no section {s}")
                after = text[m.end():m.end() + 80]
                step = re.match(r"\s*,?\s*steps?\s+(\d+)", after)
                if step and lo in secs:
                    k = step.group(1)
                    if not re.search(r"^\s*" + k + r"\.\s", secs[lo][1], re.M):
                        problems.append(f"{where}: {path} §{lo} has no step {k}")
                title = re.match(r'\s*"([^"]+)"', after)
                if title and lo in secs:
                    words = title.group(1).lower()
                    body = (secs[lo][0] + "\n" + secs[lo][1]).lower()
                    if words not in body:
                        problems.append(f"{where}: {path} §{lo} does not contain \"{title.group(1)}\"")

    problems += check_target_tests(tree)
    counts["claim"] = 1

    for p in problems:
        print(p)
    total = sum(counts.values())
    print(f"references checked: {total} ({counts['path']} paths, {counts['file:symbol']} "
          f"file:symbol, {counts['section']} section citations, {counts['claim']} claim); "
          f"unresolved: {len(problems)}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
