#!/usr/bin/env python3
"""Measures what each CTest test takes of the machine: wall time and CPU time (the test process and
every process it started and waited for), so the CPU classes in tests/CMakeLists.txt rest on
measurements (issue 40).

  scripts/test_cpu.py [--build build] [--jobs 4] [-R regex] [-E regex] [--out tests_cpu.csv]

Runs the tests CTest lists (`ctest --show-only=json-v1`, full-size twins left out), several at once
(--jobs; a waiting test's CPU time does not depend on what runs beside it, a busy one's barely),
each in its own process as CTest would, and writes one CSV row per test: name, wall [s], CPU [s],
CPU share of one core, the slots it reserves now, pass/fail. Exit 2 on bad arguments or a build
directory CTest cannot list, 1 when a test could not be started.
"""
import argparse
import concurrent.futures
import csv
import json
import os
import re
import subprocess
import sys
import time


def ctest_listing(build, *select):
    """The tests CTest lists in `build` (select: ctest's own options, e.g. "-LE", "full"), each as
    (its entry, its properties by name, the CPU slots it reserves: 0 when it reserves none).
    scripts/ctest_slots.py reads the slots from here too."""
    out = subprocess.run(["ctest", "--test-dir", build, "--show-only=json-v1", *select],
                         check=True, capture_output=True, text=True).stdout
    for t in json.loads(out)["tests"]:
        props = {p["name"]: p["value"] for p in t.get("properties", [])}
        yield t, props, sum(int(r["slots"]) for g in props.get("RESOURCE_GROUPS", []) for r in g["requirements"])


def tests_of(build, include, exclude):
    listed = []
    for t, props, slots in ctest_listing(build, "-LE", "full"):
        if include and not re.search(include, t["name"]):
            continue
        if exclude and re.search(exclude, t["name"]):
            continue
        listed.append({"name": t["name"], "command": t["command"], "cwd": props.get("WORKING_DIRECTORY", build),
                       "slots": slots or 1, "timeout": float(props.get("TIMEOUT", 900))})
    return listed


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", type=int, default=4)
    ap.add_argument("-R", dest="include")
    ap.add_argument("-E", dest="exclude")
    ap.add_argument("--out", default="tests_cpu.csv")
    args = ap.parse_args()
    if args.jobs < 1:
        print("test_cpu.py: error: --jobs must be at least 1", file=sys.stderr)
        return 2
    try:
        listed = tests_of(args.build, args.include, args.exclude)
    except (subprocess.CalledProcessError, json.JSONDecodeError, OSError) as e:
        print(f"test_cpu.py: error: cannot list the tests of build directory '{args.build}': {e}", file=sys.stderr)
        return 2
    rows = []
    try:
        with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
            for n, (test, wall, status, usage) in enumerate(pool.map(measure_children, listed), 1):
                rows.append((test, wall, status, usage))
                print(f"[{n}/{len(listed)}] {test['name']}: {wall:.1f} s wall, {usage:.1f} s CPU", flush=True)
    except OSError as e:
        print(f"test_cpu.py: error: cannot start a test: {e}", file=sys.stderr)
        return 1
    with open(args.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["test", "wall_s", "cpu_s", "cpu_share", "slots", "passed"])
        for test, wall, status, cpu in sorted(rows, key=lambda r: -r[3]):
            w.writerow([test["name"], f"{wall:.2f}", f"{cpu:.2f}", f"{cpu / max(wall, 1e-9):.3f}", test["slots"],
                        int(status == 0)])
    print(f"test_cpu.py: {len(rows)} tests, {sum(r[3] for r in rows):.0f} s of CPU in "
          f"{sum(r[1] for r in rows):.0f} s of test time; rows in {args.out}")
    return 0


def measure_children(test):
    """Runs one test and returns (test, wall, exit status, CPU seconds of it and its descendants)."""
    start = time.monotonic()
    with open(os.devnull, "wb") as null:
        proc = subprocess.Popen(test["command"], cwd=test["cwd"], stdout=null, stderr=null)
    try:
        status, usage = wait4_with_timeout(proc.pid, test["timeout"])
    except TimeoutError:
        proc.kill()
        _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = status  # reaped here: keep Popen from waiting on it again
    wall = time.monotonic() - start
    return test, wall, os.waitstatus_to_exitcode(status), usage.ru_utime + usage.ru_stime


def wait4_with_timeout(pid, timeout):
    deadline = time.monotonic() + timeout
    while True:
        got, status, usage = os.wait4(pid, os.WNOHANG)
        if got == pid:
            return status, usage
        if time.monotonic() > deadline:
            raise TimeoutError
        time.sleep(0.05)


if __name__ == "__main__":
    sys.exit(main())
