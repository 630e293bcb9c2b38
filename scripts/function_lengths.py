#!/usr/bin/env python3
"""Functions longer than the architecture allows: over 60 lines in the faces (the CLI crate's
`src/cli/` and the Python bindings' `src/`), over 120 lines anywhere else, tests excluded
(`#[cfg(test)]` blocks, `tests.rs` files, `tests/`, `benches/`, `examples/`).

A function is counted from its `fn` line to its closing brace, blank lines and comments
included (what a reader scrolls through). Prints each one over its limit and exits 1 if any.

Usage: scripts/function_lengths.py [--report] [CRATE_DIR …]   (default: every crates/*)
  --report: print the longest functions and exit 0 whatever they are.
"""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FACE_LIMIT, LIMIT = 60, 120
FN = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+)?(?:async\s+)?(?:unsafe\s+)?(?:extern\s+\"[^\"]*\"\s+)?fn\s+(\w+)")


def strip(line: str) -> str:
    """The line without its string and char literals and its `//` comment (for brace counts)."""
    line = re.sub(r'"(?:\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(?:\\.|[^'\\])'", "''", line)
    return line.split("//")[0]


def functions(path: Path):
    """(name, first line, length) of every function outside `#[cfg(test)]` items."""
    lines = path.read_text().splitlines()
    out, i, n = [], 0, len(lines)
    while i < n:
        s = lines[i].strip()
        if s.startswith("#[cfg(test)]"):
            i = skip_item(lines, i + 1)
            continue
        m = FN.match(lines[i])
        if m and not s.startswith("//"):
            end = body_end(lines, i)
            if end is not None:
                out.append((m.group(1), i + 1, end - i + 1))
        i += 1
    return out


def body_end(lines, start):
    """The line index of the brace closing the function starting at `start` (None: no body)."""
    depth, opened = 0, False
    for j in range(start, len(lines)):
        t = strip(lines[j])
        if not opened and ";" in t and "{" not in t:
            return None
        depth += t.count("{") - t.count("}")
        opened = opened or "{" in t
        if opened and depth <= 0:
            return j
    return None


def skip_item(lines, i):
    """The index after the item starting at line `i` (a braced block or one line)."""
    depth, opened = 0, False
    while i < len(lines):
        t = strip(lines[i])
        depth += t.count("{") - t.count("}")
        opened = opened or "{" in t
        i += 1
        if (opened and depth <= 0) or (not opened and t.rstrip().endswith(";")):
            return i
    return i


def limit_of(crate: Path, f: Path) -> int:
    rel = f.relative_to(crate)
    face = (crate.name == "aeroident" and rel.parts[:2] == ("src", "cli")) or crate.name == "python"
    return FACE_LIMIT if face else LIMIT


def main():
    args = sys.argv[1:]
    report = "--report" in args
    crates = [Path(a).resolve() for a in args if a != "--report"] or sorted((ROOT / "crates").iterdir())
    rows = []
    for c in crates:
        for f in sorted((c / "src").rglob("*.rs")):
            if f.name == "tests.rs" or "tests" in f.relative_to(c / "src").parts[:-1]:
                continue
            lim = limit_of(c, f)
            for name, line, length in functions(f):
                rows.append((length, lim, f.relative_to(ROOT), line, name))
    over = [r for r in rows if r[0] > r[1]]
    shown = sorted(rows, reverse=True)[:30] if report else sorted(over, reverse=True)
    for length, lim, f, line, name in shown:
        print(f"{f}:{line}: fn {name}: {length} lines (limit {lim})")
    print(f"{len(over)} functions over their limit")
    sys.exit(0 if report or not over else 1)


if __name__ == "__main__":
    main()
