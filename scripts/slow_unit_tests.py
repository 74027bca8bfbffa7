#!/usr/bin/env python3
"""Prints a gtest negative filter ("-A.b:C.d") of the unit tests that took at least SECONDS in the
gtest XML results of a run (the normal build's, in RESULTS), except those named after it (KEEP,
gtest patterns): CI runs the unit tests under the sanitizers, some 50 times slower, without them
(.ci/run, docs/reliability.md). Prints each one left out, with its time, on standard error.
Exit status 1 when RESULTS holds no gtest result."""
import fnmatch
import pathlib
import sys
import xml.etree.ElementTree as ET


def main(results, seconds, keep):
    files = sorted(pathlib.Path(results).glob("gtest-*.xml"))
    if not files:
        print(f"no gtest-*.xml in {results}", file=sys.stderr)
        return 1
    slow = []
    for path in files:
        for case in ET.parse(path).getroot().iter("testcase"):
            time = float(case.get("time", "0"))
            name = f"{case.get('classname')}.{case.get('name')}"
            if time >= seconds and not any(fnmatch.fnmatchcase(name, pattern) for pattern in keep):
                slow.append((time, name))
    for time, name in sorted(slow, reverse=True):
        print(f"left out under the sanitizers: {name} ({time:.1f} s in the normal build)", file=sys.stderr)
    print("-" + ":".join(name for _, name in sorted(slow, key=lambda s: s[1])))
    return 0


if __name__ == "__main__":
    if len(sys.argv) < 3:
        print("usage: slow_unit_tests.py RESULTS SECONDS [KEEP ...]", file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1], float(sys.argv[2]), sys.argv[3:]))
