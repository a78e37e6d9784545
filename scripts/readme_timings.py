#!/usr/bin/env python3
"""Measure the built-in scene's run time and write it into README.md.

Runs `build/pstencil run` (the built-in scene) several times, takes the median of each timer it
prints (cloud, neighbour list, precompute, each task, total) and replaces the text between the
README's run-timings markers with them, the date, the thread count and the machine's load. The
README's "about N s" is this script's output, never a typed number. Run it on an idle machine:

    python3 scripts/readme_timings.py [--runs 5] [--binary build/pstencil] [--dry-run]
"""
import argparse
import datetime
import os
import re
import statistics
import subprocess
import sys

BEGIN, END = "<!-- run-timings:begin -->", "<!-- run-timings:end -->"
TIMER = re.compile(r"^\s+(cloud|neighbours|total)\s+([0-9.]+) s$")
PRECOMPUTE = re.compile(r"precompute ([0-9.]+) s")
TASK = re.compile(r"^\s+task (\S+) \(.*, ([0-9.]+) s$")


def one_run(binary):
    """The timers of one run, in seconds, by name."""
    out = subprocess.run([binary, "run"], check=True, capture_output=True, text=True).stdout
    timers, threads = {}, None
    for line in out.splitlines():
        m = TIMER.match(line) or TASK.match(line)
        if m:
            timers[m.group(1)] = float(m.group(2))
        m = PRECOMPUTE.search(line)
        if m:
            timers["precompute"] = float(m.group(1))
        m = re.search(r"particles, (\d+) threads", line)
        if m:
            threads = int(m.group(1))
    if "total" not in timers or threads is None:
        sys.exit("readme_timings: the run printed no timers:\n" + out)
    return timers, threads


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--binary", default="build/pstencil")
    ap.add_argument("--readme", default="README.md")
    ap.add_argument("--dry-run", action="store_true", help="print the text, leave README.md")
    a = ap.parse_args()
    if not 1 <= a.runs <= 50:
        sys.exit("readme_timings: --runs must be 1 to 50")
    load = os.getloadavg()[0]
    runs = [one_run(a.binary) for _ in range(a.runs)]
    threads = runs[0][1]
    med = {k: statistics.median(r[0][k] for r in runs) for k in runs[0][0]}
    parts = [f"{k.replace('neighbours', 'neighbour list')} {med[k]:.2f} s"
             for k in med if k not in ("total",)]
    text = (f"{BEGIN}about {med['total']:.1f} s on {threads} cores ({', '.join(parts)}; medians "
            f"of {a.runs} runs by `scripts/readme_timings.py`, {datetime.date.today()}, load "
            f"average {load:.1f} at the start){END}")
    if a.dry_run:
        print(text)
        return
    with open(a.readme, encoding="utf-8") as f:
        readme = f.read()
    pat = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.S)
    if len(pat.findall(readme)) != 1:
        sys.exit(f"readme_timings: {a.readme} needs exactly one {BEGIN} ... {END} block")
    with open(a.readme + ".tmp", "w", encoding="utf-8") as f:
        f.write(pat.sub(lambda _: text, readme))
    os.replace(a.readme + ".tmp", a.readme)
    print(text)


if __name__ == "__main__":
    main()
