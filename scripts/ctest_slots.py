#!/usr/bin/env python3
"""How a CTest run used the CPU slots its tests reserve (issue 40): from the run's own output (the
"Start N: name" and "k/n Test #N: name ... Passed x sec" lines, as scripts/test.sh prints them) and
the slots each test reserves (`ctest --show-only=json-v1` of the same build), rebuilds when each
test ran and prints the slots in use over time, the share of slot-seconds used, and the
slot-seconds by class.

  scripts/ctest_slots.py LOG [--build build] [--step 20] [--pass N]

--pass picks one CTest pass of a log with several (scripts/test.sh --full: 2, the full-size twins).
A test starts when CTest prints its Start line and ends its duration later; CTest prints a Start
line right after a test ends (when its slots come free), so a Start line's time is the latest end
printed before it. The machine's slots are build/resources.json's. Exit 2 on a missing log, a log
with no test results, or a build CTest cannot list or without resources.json.
"""
import argparse
import json
import re
import subprocess
import sys

from test_cpu import ctest_listing

START = re.compile(r"\s*Start\s+\d+: (\S+)")
DONE = re.compile(r"\s*\d+/\d+ Test\s+#\d+: (\S+) .*?([0-9.]+) sec")


def slots_of(build):
    """Each test's slots by its name as the log prints it (without a parameter's " # GetParam() ...")."""
    return {t["name"].split(" ")[0]: slots for t, _, slots in ctest_listing(build)}


def passes_of(lines):
    """Per CTest pass (scripts/test.sh ends each with a "test.sh:" line): (name, start, end) per
    test, in the order they ended."""
    passes, now, started, runs = [], 0.0, {}, []
    for line in lines:
        if line.startswith("test.sh:") and runs:  # the pass's own time line: the next one starts at 0
            passes.append(runs)
            now, started, runs = 0.0, {}, []
        m = START.match(line)
        if m:
            started[m.group(1)] = now
            continue
        m = DONE.match(line)
        if m and m.group(1) in started:
            end = started[m.group(1)] + float(m.group(2))
            now = max(now, end)
            runs.append((m.group(1), started[m.group(1)], end))
    return passes + [runs] if runs else passes


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("log")
    ap.add_argument("--build", default="build")
    ap.add_argument("--step", type=int, default=20, help="seconds per printed row")
    ap.add_argument("--pass", dest="which", type=int, default=1,
                    help="which CTest pass of the log (1: the default suite; --full's twins: 2)")
    a = ap.parse_args()
    try:
        with open(a.log, encoding="utf-8", errors="replace") as f:
            passes = passes_of(f.read().splitlines())
        slots = slots_of(a.build)
        with open(f"{a.build}/resources.json", encoding="utf-8") as f:  # the machine's slots, as CTest had them
            capacity = sum(int(c["slots"]) for node in json.load(f)["local"] for c in node["cpu"])
    except (OSError, KeyError, ValueError, subprocess.CalledProcessError) as e:
        print(f"ctest_slots.py: error: {e}", file=sys.stderr)
        return 2
    if not 1 <= a.which <= len(passes) or a.step < 1:
        print(f"ctest_slots.py: error: {a.log}: no CTest pass {a.which} with test results"
              f" ({len(passes)} passes; or --step < 1)", file=sys.stderr)
        return 2
    runs = passes[a.which - 1]
    total = int(max(end for _, _, end in runs)) + 1
    used = [0] * total
    by_class = {}
    for name, start, end in runs:
        k = slots.get(name, 0)
        for t in range(int(start), int(end)):
            used[t] += k
        c = by_class.setdefault(k, [0, 0.0])
        c[0] += 1
        c[1] += end - start
    print(f"{len(runs)} tests in {total} s; slot-seconds reserved {sum(used)} of {capacity * total}"
          f" ({100 * sum(used) / (capacity * total):.0f} %)")
    print("from [s]  slots in use (mean)  tests of 6 slots or more")
    for at in range(0, total, a.step):
        part = used[at:at + a.step]
        wide = [n for n, s, e in runs if s <= at < e and slots.get(n, 0) >= 6]
        print(f"{at:8d}  {sum(part) / len(part):19.1f}  {', '.join(wide)}")
    for k, (n, seconds) in sorted(by_class.items()):
        print(f"{k:2d} slots: {n:3d} tests, {seconds:6.0f} s, {k * seconds:6.0f} slot-seconds")
    return 0


if __name__ == "__main__":
    sys.exit(main())
