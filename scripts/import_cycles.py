#!/usr/bin/env python3
"""Import cycles between the modules of each workspace crate.

A module is one source file (`src/a/b.rs` or `src/a/b/mod.rs` is `a::b`); it imports every
module it names through `crate::…`, `super::…` or `self::…` paths, and through bare paths
whose first segment is one of its own child modules (`outliers::SpikeScreen` in the module
that declares `mod outliers;`, `cli::run` in `main.rs`), outside its own `#[cfg(test)]` block
and comments. Prints each strongly connected component of more than
one module (a cycle) and exits 1 if there is any.

Usage: scripts/import_cycles.py [CRATE_DIR …]   (default: every crates/*)
"""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def module_of(src: Path, f: Path) -> tuple:
    parts = list(f.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("mod", "lib", "main"):
        parts = parts[:-1]
    return tuple(parts)


def code_lines(text: str):
    """The file's lines outside `#[cfg(test)] mod … { … }` and comments."""
    out, depth, skipping = [], 0, False
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if not skipping and line.strip().startswith("#[cfg(test)]"):
            skipping, depth = True, 0
            i += 1
            continue
        if skipping:
            depth += line.count("{") - line.count("}")
            if depth <= 0 and "}" in line:
                skipping = False
            i += 1
            continue
        stripped = line.strip()
        if not stripped.startswith("//"):
            out.append(line.split("//")[0])
        i += 1
    return out


def resolve(path: list, here: tuple, modules: set) -> tuple | None:
    """The longest existing module named by a `crate::`/`super::`/`self::` path."""
    if path[0] == "crate":
        base, rest = (), path[1:]
    else:
        base = here
        rest = path
        while rest and rest[0] in ("super", "self"):
            if rest[0] == "super":
                base = base[:-1]
            rest = rest[1:]
    best = None
    for k in range(len(rest) + 1):
        cand = base + tuple(rest[:k])
        if cand in modules:
            best = cand
    return best


def graph(crate: Path):
    src = crate / "src"
    files = {module_of(src, f): f for f in src.rglob("*.rs")}
    modules = set(files)
    edges = {m: set() for m in modules}
    pat = re.compile(r"\b((?:crate|super|self)(?:::\w+)+)")
    group = re.compile(r"\b((?:crate|super|self)(?:::\w+)*)::\{([^}]*)\}")
    # A bare path not preceded by `::`, a letter or a digit (so not a tail of `a::b::c`).
    bare = re.compile(r"(?<![:\w])([a-z_]\w*(?:::\w+)+)")
    bare_group = re.compile(r"(?<![:\w])([a-z_]\w*(?:::\w+)*)::\{([^}]*)\}")
    for m, f in files.items():
        # Module files named `tests` hold the parent's unit tests.
        if m and m[-1] == "tests":
            continue
        text = "\n".join(code_lines(f.read_text()))
        paths = [p.split("::") for p in pat.findall(text)]
        children = {c[-1] for c in modules if len(c) == len(m) + 1 and c[: len(m)] == m}
        for p in bare.findall(text):
            segs = p.split("::")
            if segs[0] in children:
                paths.append(["self"] + segs)
        for prefix, items in bare_group.findall(text):
            segs = prefix.split("::")
            if segs[0] in children:
                paths.extend(["self"] + segs + i.strip().split(" as ")[0].split("::")
                             for i in items.split(",") if i.strip() and i.strip() != "self")
        for prefix, items in group.findall(text):
            for item in items.split(","):
                item = item.strip().split(" as ")[0]
                if item and item != "self":
                    paths.append(prefix.split("::") + item.split("::"))
        for p in paths:
            # `self` is the module itself and `super` its parent, whichever file holds it; a
            # module using its own ancestors is not a cycle (they declare it).
            target = resolve(p, m, modules)
            if target is not None and target != m and target != m[: len(target)]:
                edges[m].add(target)
    return edges


def sccs(edges):
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(comp)

    sys.setrecursionlimit(10000)
    for v in edges:
        if v not in index:
            visit(v)
    return [c for c in out if len(c) > 1]


def main():
    crates = [Path(a) for a in sys.argv[1:]] or sorted((ROOT / "crates").iterdir())
    found = 0
    for c in crates:
        if not (c / "src").is_dir():
            continue
        for comp in sccs(graph(c)):
            found += 1
            names = sorted("::".join(m) or "(root)" for m in comp)
            print(f"{c.name}: cycle among {', '.join(names)}")
    print(f"{found} import cycles")
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
