#!/usr/bin/env python3
"""Capture the outputs of every example scene, and compare two captures byte for byte.

A refactoring must not change what pstencil computes. `capture` runs every scene in scenes/
(and a few commands that write files: apply, stencil, analyse) with one build of the program
and keeps every file they write; `compare` says which files differ between two captures.
Timings are the only thing allowed to differ, so JSON files are compared after removing the
keys that hold wall-clock or memory readings (TIMING_KEYS); every other file must be equal to
the byte.

    python3 scripts/check_outputs.py capture BUILD/pstencil DIR    # before the change
    python3 scripts/check_outputs.py capture BUILD/pstencil DIR2   # after it
    python3 scripts/check_outputs.py compare DIR DIR2               # exit 1 on any difference
"""
import json
import math
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# keys whose values are readings of the machine, not results
TIMING_KEYS = {"timers", "phases", "seconds", "setup_seconds", "peak_rss_bytes", "available", "cpu", "wall",
               "machine", "time", "elapsed"}


def commands():
    """(name, steps) of every run: each step is the program's arguments, or a Python function
    of the run's folder (to prepare an input file)."""
    runs = []
    for f in sorted(os.listdir(os.path.join(ROOT, "scenes"))):
        if f.endswith(".json"):
            # a report and a VTU from every scene, besides the outputs it names itself
            runs.append((f[:-5], [["run", os.path.join(ROOT, "scenes", f),
                                   "outputs.report=all.report.json", "outputs.vtu=all.vtu"]]))
    cloud = ["cloud", "--dim", "2", "--s0", "0.05", "--jitter", "0.3", "-o", "cloud.csv"]
    for scheme in ("lv", "qsfdi", "mixed1", "cspm"):
        runs.append(("apply_" + scheme, [
            cloud, add_field,
            ["apply", "--scheme", scheme, "--in", "cloud.csv", "--field", "u", "--out", "Lu.csv"],
            ["stencil", "--scheme", scheme, "--in", "cloud.csv", "--out", "A.mtx"]]))
    runs.append(("analyse_lv_patch", [["analyse", os.path.join(ROOT, "scenes", "lv_patch_2d.json"),
                                       "--out", "analysis"]]))
    return runs


def add_field(here):
    """Append the column u = sin(3x) y^2 to cloud.csv (repr: the same digits every time)."""
    path = os.path.join(here, "cloud.csv")
    with open(path) as f:
        lines = f.read().splitlines()
    head = lines[0].split(",")
    ix, iy = head.index("x"), head.index("y")
    out = [lines[0] + ",u"]
    for line in lines[1:]:
        v = line.split(",")
        out.append(line + "," + repr(math.sin(3 * float(v[ix])) * float(v[iy]) ** 2))
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return "add_field", 0


def capture(program, out):
    program = os.path.abspath(program)
    if os.path.exists(out):
        shutil.rmtree(out)
    os.makedirs(out)
    failed = 0
    for name, argv in commands():
        here = os.path.join(out, name)
        os.makedirs(here)
        with open(os.path.join(here, "exit_codes.txt"), "w") as codes:
            for step in argv:
                if callable(step):
                    codes.write("%s: %d\n" % step(here))
                    continue
                # the console lines carry timings; the exit code and the files are the result
                p = subprocess.run([program, "--threads", "2", "--quiet"] + step, cwd=here,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                codes.write("%s: %d\n" % (step[0], p.returncode))
                if p.returncode not in (0, 3):
                    failed += 1
                    sys.stderr.write("%s: %s exited %d: %s\n" % (name, step[0], p.returncode,
                                                                 p.stderr.strip()))
        print("captured", name)
    return 1 if failed else 0


def strip_timings(obj):
    if isinstance(obj, dict):
        return {k: strip_timings(v) for k, v in obj.items() if k not in TIMING_KEYS}
    if isinstance(obj, list):
        return [strip_timings(v) for v in obj]
    return obj


def comparable(path):
    with open(path, "rb") as f:
        data = f.read()
    if path.endswith(".json"):
        try:
            return json.dumps(strip_timings(json.loads(data)), sort_keys=True).encode()
        except ValueError:
            return data
    return data


def files_under(top):
    found = set()
    for d, _, names in os.walk(top):
        for n in names:
            found.add(os.path.relpath(os.path.join(d, n), top))
    return found


def compare(a, b):
    fa, fb = files_under(a), files_under(b)
    bad = 0
    for f in sorted(fa ^ fb):
        print("only in one capture:", f)
        bad += 1
    for f in sorted(fa & fb):
        if comparable(os.path.join(a, f)) != comparable(os.path.join(b, f)):
            print("differs:", f)
            bad += 1
    print("%d files compared, %d differences" % (len(fa & fb), bad))
    return 1 if bad else 0


def main(argv):
    if len(argv) == 4 and argv[1] == "capture":
        return capture(argv[2], argv[3])
    if len(argv) == 4 and argv[1] == "compare":
        return compare(argv[2], argv[3])
    sys.stderr.write(__doc__)
    return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
