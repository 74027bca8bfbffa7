#!/usr/bin/env python3
"""Splits a unit-test binary's tests into SHARDS gtest filters of about equal time, from the times of
an earlier run: reads the binary's `--gtest_list_tests` on standard input and the gtest XML results
in TIMES (gtest-*.xml), and prints one positive filter ("A.b:C.d") per line, SHARDS lines. Longest
test first, each to the shard with the least time so far (a test missing from TIMES counts the median
of those found); a shard with no test prints "-*" (runs nothing). scripts/test uses it when
PARTICLE_SIM_TEST_TIMES is set: gtest's own sharding deals the tests out in turn, whatever they cost,
so under the sanitizers one shard could run for twice as long as the other."""
import heapq
import pathlib
import statistics
import sys
import xml.etree.ElementTree as ET


def listed_tests(lines):
    """The full names of `--gtest_list_tests` output: "Suite." lines, then "  Test" lines."""
    tests, suite = [], ""
    for line in lines:
        name = line.split("#", 1)[0].rstrip()
        if not name:
            continue
        if line.startswith(" "):
            tests.append(suite + name.strip())
        else:
            suite = name
    return tests


def recorded_times(results):
    times = {}
    for path in sorted(pathlib.Path(results).glob("gtest-*.xml")):
        for case in ET.parse(path).getroot().iter("testcase"):
            times[f"{case.get('classname')}.{case.get('name')}"] = float(case.get("time", "0"))
    return times


def balance(tests, times, shards):
    known = [times[t] for t in tests if t in times]
    default = statistics.median(known) if known else 1.0
    loads = [(0.0, shard) for shard in range(shards)]
    members = [[] for _ in range(shards)]
    for test in sorted(tests, key=lambda t: (-times.get(t, default), t)):
        load, shard = heapq.heappop(loads)
        members[shard].append(test)
        heapq.heappush(loads, (load + times.get(test, default), shard))
    return [":".join(sorted(group)) if group else "-*" for group in members]


def main(results, shards):
    for line in balance(listed_tests(sys.stdin), recorded_times(results), shards):
        print(line)
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3 or not sys.argv[2].isdigit() or int(sys.argv[2]) < 1:
        print("usage: BINARY --gtest_list_tests | balance_shards.py TIMES SHARDS", file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1], int(sys.argv[2])))
