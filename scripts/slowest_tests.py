#!/usr/bin/env python3
"""Ranks the tests of a cargo-nextest JUnit report by time: the slowest N, each binary's total,
and the run's total, so that where CI's test time goes is in its log.

Usage: slowest_tests.py JUNIT.xml [N]   (N: how many tests to list, default 30)
"""
import sys
import xml.etree.ElementTree as ET
from collections import defaultdict


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
    tests, per_binary = [], defaultdict(float)
    for suite in root.iter("testsuite"):
        for case in suite.iter("testcase"):
            t = float(case.get("time", "0") or 0)
            binary = suite.get("name", "?")
            tests.append((t, binary, case.get("name", "?")))
            per_binary[binary] += t
    tests.sort(reverse=True)
    total = sum(t for t, _, _ in tests)
    print(f"{len(tests)} tests, {total:.0f} s of test time (summed over parallel runs)")
    print(f"slowest {min(n, len(tests))}:")
    for t, binary, name in tests[:n]:
        print(f"  {t:8.1f} s  {binary}  {name}")
    print("per test binary (top 15):")
    for binary, t in sorted(per_binary.items(), key=lambda kv: -kv[1])[:15]:
        print(f"  {t:8.1f} s  {binary}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
