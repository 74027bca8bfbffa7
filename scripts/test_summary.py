#!/usr/bin/env python3
"""Summarises the JUnit XML files in a directory: prints each failed test's name and ends with
'N passed, N failed'. Exit status 1 when anything failed, a result file is missing or no test ran."""
import pathlib
import sys
import xml.etree.ElementTree as ET


def main(directory):
    root = pathlib.Path(directory)
    passed, failed = 0, []
    for path in sorted(root.rglob("*.xml")):
        try:
            tree = ET.parse(path)
        except ET.ParseError as error:
            failed.append(f"{path.name} (unreadable result file: {error})")
            continue
        # A rostest-*.xml file wraps the run of one .test file: its one test case only says
        # whether the inner tests (in their own rosunit-*.xml) produced results, so only its
        # failures count.
        wrapper = path.name.startswith("rostest-")
        for case in tree.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}".strip(".")
            if case.find("skipped") is not None or case.get("status") == "notrun":
                failed.append(f"{name} (skipped)")
            elif case.find("failure") is not None or case.find("error") is not None:
                failed.append(name)
            elif not wrapper:
                passed += 1
    missing = root / "MISSING"
    if missing.exists():
        failed += [f"{line} (crashed or wrote no result)" for line in missing.read_text().split("\n") if line]
    for name in failed:
        print(f"FAILED: {name}")
    print(f"{passed} passed, {len(failed)} failed")
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
