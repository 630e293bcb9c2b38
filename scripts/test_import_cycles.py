#!/usr/bin/env python3
"""Self-test of scripts/import_cycles.py on small made-up crates: a cycle through `crate::`
paths, one through a bare child path (`child::f` in the parent that declares it, back through a
third module: a child using its own ancestors is not a cycle), one through a grouped bare
import, and code that must not count (a tail of an extern path, a test block,
a comment). Exit 0 when every case is judged as expected."""
import subprocess
import sys
import tempfile
from pathlib import Path

SCRIPT = Path(__file__).resolve().parent / "import_cycles.py"


def crate(files: dict) -> Path:
    root = Path(tempfile.mkdtemp()) / "c"
    for name, text in files.items():
        f = root / "src" / name
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text)
    return root


CASES = [
    ("crate paths", True, {
        "lib.rs": "pub mod a;\npub mod b;\n",
        "a.rs": "use crate::b::g;\npub fn f() {}\n",
        "b.rs": "pub fn g() { crate::a::f() }\n",
    }),
    ("bare child path", True, {
        "lib.rs": "pub mod p;\npub mod q;\n",
        "p/mod.rs": "pub mod child;\npub fn h() { child::f() }\n",
        "p/child.rs": "pub fn f() { crate::q::k() }\n",
        "q.rs": "pub fn k() { crate::p::h() }\n",
    }),
    ("grouped bare import", True, {
        "lib.rs": "pub mod p;\npub mod q;\n",
        "p/mod.rs": "mod child;\nuse child::{f, g};\npub fn h() {}\n",
        "p/child.rs": "use crate::q::k;\npub fn f() {}\npub fn g() {}\n",
        "q.rs": "pub fn k() { crate::p::h() }\n",
    }),
    ("no cycle: extern tail, test block, comment", False, {
        "lib.rs": "pub mod a;\npub mod b;\n",
        "a.rs": "use crate::b::g;\npub fn f() { other::b::x(); }\n// crate::b is fine to name here\n",
        "b.rs": ("pub fn g() { ext::a::y(); }\n// crate::a::f in a comment\n"
                 "#[cfg(test)]\nmod tests {\n    use crate::a::f;\n}\n"),
    }),
]


def main():
    failed = 0
    for name, cyclic, files in CASES:
        r = subprocess.run([sys.executable, str(SCRIPT), str(crate(files))],
                           capture_output=True, text=True)
        ok = (r.returncode == 1) == cyclic
        failed += not ok
        print(f"{'ok' if ok else 'FAILED'}: {name}: exit {r.returncode}: {r.stdout.strip()}")
    print(f"{len(CASES) - failed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
