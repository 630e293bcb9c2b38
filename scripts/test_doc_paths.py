#!/usr/bin/env python3
"""Self-test of scripts/doc_paths.py on a small made-up repository: a document citing paths
that exist (a file, a directory, a file with a Rust item, a line number or an anchor after it,
a crate-relative `pipelines/src/…` path, a path closing a sentence) passes; one citing a
missing file, a missing crate-relative file or a missing top directory's file fails, naming
each; and what is not a path of this tree is never reported (a placeholder, an output or build
directory, a path inside another path). Exit 0 when every case is judged as expected."""
import subprocess
import sys
import tempfile
from pathlib import Path

SCRIPT = Path(__file__).resolve().parent / "doc_paths.py"

TREE = [
    "crates/pipelines/src/replay/mod.rs",
    "crates/pipelines/tests/export.rs",
    "crates/aeroident/src/main.rs",
    "scripts/check.py",
    "docs/mapping.md",
    "mappings/hfb320.toml",
    "scenarios/default.toml",
]


def repo(doc: str) -> Path:
    root = Path(tempfile.mkdtemp())
    for f in TREE:
        (root / f).parent.mkdir(parents=True, exist_ok=True)
        (root / f).write_text("\n")
    (root / "docs" / "guide.md").write_text(doc)
    return root


# (name, document, the missing paths expected in the report, in order)
CASES = [
    ("existing paths in every form", (
        "See `crates/pipelines/src/replay/mod.rs::replay` and crates/pipelines/tests/.\n"
        "Run scripts/check.py, read [the mapping](docs/mapping.md#units) and\n"
        "`mappings/hfb320.toml:12`; the default is scenarios/default.toml.\n"
        "Tests: `pipelines/src/replay/mod.rs::errors_x`, `pipelines/tests/export.rs`.\n"
    ), []),
    ("missing files, full and crate-relative", (
        "Moved: `crates/pipelines/src/replay/derivatives.rs::f` and\n"
        "`aeroident/src/outdir.rs::second_run` and scripts/gone.sh.\n"
    ), ["docs/guide.md:1: crates/pipelines/src/replay/derivatives.rs",
        "docs/guide.md:2: aeroident/src/outdir.rs",
        "docs/guide.md:2: scripts/gone.sh"]),
    ("not paths of this tree", (
        "crates/*/README*, `crates/<crate>/src/`, scenarios/{a,b}.toml, crates/pipelines/src/…\n"
        "aeroident-out/docs/x.md, `../shared/scenarios/x.toml`, target/docs/x, docs/OUT/a.md,\n"
        "`docs/DIR/summary.json`, my-run-out/scripts/x, crates/x/target/debug/y\n"
    ), []),
]


def main():
    failed = 0
    for name, doc, expected in CASES:
        r = subprocess.run([sys.executable, str(SCRIPT), "--root", str(repo(doc))],
                           capture_output=True, text=True)
        reported = [l for l in r.stdout.splitlines() if l.startswith("docs/guide.md:")]
        ok = reported == expected and (r.returncode == 1) == bool(expected)
        failed += not ok
        print(f"{'ok' if ok else 'FAILED'}: {name}: exit {r.returncode}"
              + ("" if ok else f": got {reported}, expected {expected}\n{r.stdout}{r.stderr}"))
    print(f"{len(CASES) - failed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
