#!/usr/bin/env python3
"""Repository paths the documentation cites that do not exist.

A cited path is a token that starts with one of the repository's top directories (`crates/`,
`scripts/`, `scenarios/`, `mappings/`, `docs/`, `examples/`, `models/`), or with a crate's
directory and one of its source folders (`pipelines/src/…`, `io/tests/…`, short for
`crates/pipelines/src/…`), where no other path character comes before it (so
`../shared/scenarios/x` and `aeroident-out/docs/x` are not paths of this repository). A Rust item after the file (`batch.rs::config`), a line number
(`log.rs:42`), an anchor (`mapping.md#units`) and trailing punctuation are dropped before the
path is looked up. Left out, as not naming one file of the tree: paths with a placeholder
(`*`, `<`, `{`, `…`, `...`), and paths through build or example output directories (`target/`,
`aeroident-out/`, `DIR/`, `OUT/`, any `*-out/`). Code blocks are read too: a command that
names a file that has moved fails as surely as prose that does.

Prints `file:line: path` for each missing path and exits 1 if there is any. When a path is
gone, `git log --follow -- PATH` or `git log --diff-filter=R --name-status` says where it went.

Usage: scripts/doc_paths.py [--root DIR] [FILE.md …]
       (default: README.md, docs/**/*.md and crates/*/README.md under the root, the repository
       by default)
"""
import re
import sys
from pathlib import Path

TOP = ("crates", "scripts", "scenarios", "mappings", "docs", "examples", "models")
# A path token: a top directory, a slash, then anything up to a character no cited path holds.
# The look-behind refuses a token inside a longer path or word (`../shared/scenarios/x`,
# `aeroident-out/docs`, `sub-crates/`).
BEFORE = r"(?<![\w./~$-])"
TAIL = r"[^\s`'\"()\[\],;|]*"
PATH = re.compile(BEFORE + r"(?:%s)/" % "|".join(TOP) + TAIL)
CRATE_DIRS = ("src", "tests", "benches", "examples", "python")
PLACEHOLDER = ("*", "<", ">", "{", "}", "…", "...", "$")
OUTPUT_DIRS = {"target", "aeroident-out", "DIR", "OUT"}


def clean(token: str) -> str:
    """The file part of a cited token: no Rust item, line number, anchor or trailing stop."""
    path = token.split("::")[0].split("#")[0]
    path = re.sub(r":\d+(?:[-:]\d+)?$", "", path)
    return path.rstrip(".:!?")


def skipped(path: str) -> bool:
    if any(p in path for p in PLACEHOLDER):
        return True
    parts = path.split("/")
    return any(p in OUTPUT_DIRS or p.endswith("-out") for p in parts)


def crate_path(root: Path):
    """Tokens `<crate>/<source folder>/…` of the crates under `root`, short for `crates/…`."""
    crates = sorted(d.name for d in (root / "crates").iterdir() if d.is_dir()) \
        if (root / "crates").is_dir() else []
    if not crates:
        return None
    return re.compile(BEFORE + r"(?:%s)/(?:%s)\b" % ("|".join(map(re.escape, crates)),
                                                   "|".join(CRATE_DIRS)) + TAIL)


def missing_in(md: Path, root: Path, short=None):
    """(line number, path) of each cited path of `md` absent under `root` (`short`: the
    pattern of crate-relative paths, [`crate_path`]). A token both patterns match
    (`models/src/…`: the top directory `models/` or the crate) is there if either is."""
    out = []
    for n, line in enumerate(md.read_text(encoding="utf-8").splitlines(), 1):
        cited = {}
        for m in PATH.finditer(line):
            cited.setdefault(m.start(), (m.group(0), [""]))
        for m in short.finditer(line) if short is not None else ():
            token, bases = cited.get(m.start(), (m.group(0), []))
            cited[m.start()] = (max(token, m.group(0), key=len), ["crates/"] + bases)
        for _, (token, bases) in sorted(cited.items()):
            path = clean(token)
            if path.rstrip("/") in TOP or skipped(path):
                continue
            if not any((root / base / path).exists() for base in bases):
                out.append((n, path))
    return out


def default_files(root: Path):
    files = [root / "README.md"] if (root / "README.md").exists() else []
    files += sorted((root / "docs").rglob("*.md"))
    files += sorted((root / "crates").glob("*/README.md"))
    return files


def main(argv):
    root = Path(__file__).resolve().parent.parent
    if argv[:1] == ["--root"]:
        root, argv = Path(argv[1]).resolve(), argv[2:]
    files = [Path(a) for a in argv] or default_files(root)
    short, bad = crate_path(root), 0
    for md in files:
        for n, path in missing_in(md, root, short):
            try:
                shown = md.resolve().relative_to(root)
            except ValueError:
                shown = md
            print(f"{shown}:{n}: {path}")
            bad += 1
    if bad:
        print(f"{bad} cited path(s) missing (git log --follow -- PATH says where each went)")
        return 1
    print(f"doc paths OK ({len(files)} files)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
