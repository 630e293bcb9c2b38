#!/usr/bin/env python3
"""Ranks the tests of a cargo-nextest JUnit report by time: the slowest N, the total of each
integration-test file and of each unit-test binary, and the run's total, so that where CI's
test time goes is in its log. A crate's integration tests are one binary (`<crate>::all`,
tests/all/main.rs) whose modules are the files: a file's total is that of the tests under its
module (`aeroident-io::all fuzz_parsers`).

Usage: slowest_tests.py JUNIT.xml [N]   (N: how many tests to list, default 30)
"""
import sys
import xml.etree.ElementTree as ET
from collections import defaultdict


def test_file(binary: str, name: str) -> str:
    """The binary and, for an integration-test binary (`crate::all`), the module of `name`: the
    file under tests/all/ the test is in. nextest names an integration-test binary
    `crate::name`, a binary's unit tests `crate::bin/name`, a library's `crate`."""
    _, _, target = binary.partition("::")
    if target and "/" not in target and "::" in name:
        return f"{binary} {name.split('::', 1)[0]}"
    return binary


def main() -> int:
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    path, n = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 30
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        print(f"slowest_tests: {path}: {e}", file=sys.stderr)
        return 1
    tests, per_file = [], defaultdict(float)
    for suite in root.iter("testsuite"):
        for case in suite.iter("testcase"):
            t = float(case.get("time", "0") or 0)
            binary, name = suite.get("name", "?"), case.get("name", "?")
            tests.append((t, binary, name))
            per_file[test_file(binary, name)] += t
    tests.sort(reverse=True)
    total = sum(t for t, _, _ in tests)
    print(f"{len(tests)} tests, {total:.0f} s of test time (summed over parallel runs)")
    print(f"slowest {min(n, len(tests))}:")
    for t, binary, name in tests[:n]:
        print(f"  {t:8.1f} s  {binary}  {name}")
    print("per test file or unit-test binary (top 15):")
    for file, t in sorted(per_file.items(), key=lambda kv: -kv[1])[:15]:
        print(f"  {t:8.1f} s  {file}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
