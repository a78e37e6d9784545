#!/usr/bin/env python3
"""Measure the README's run and sweep times and write them into README.md.

Runs `build/pstencil run` (the built-in scene) several times, takes the median of each timer it
prints (cloud, neighbour list, precompute, each task, total) and replaces the text between the
README's run-timings markers with them, the date, the thread count and the machine's load. Then
runs the README's sweep (scenes/sweeps/qsfdi_fig1_test_a.json, in a scratch folder) as many
times and writes the median wall time between the sweep-timings markers. The README's "about N
s" and "in N s" are this script's output, never typed numbers. Run it on an idle machine:

    python3 scripts/readme_timings.py [--runs 5] [--binary build/pstencil] [--dry-run]
"""
import argparse
import datetime
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

BEGIN, END = "<!-- run-timings:begin -->", "<!-- run-timings:end -->"
SWEEP_BEGIN, SWEEP_END = "<!-- sweep-timings:begin -->", "<!-- sweep-timings:end -->"
SWEEP = "scenes/sweeps/qsfdi_fig1_test_a.json"
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


def one_sweep(binary):
    """The wall time of the README's sweep, run in a scratch folder (it writes its CSV there)."""
    binary, sweep = os.path.abspath(binary), os.path.abspath(SWEEP)
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        subprocess.run([binary, "--quiet", "sweep", sweep], check=True, cwd=d)
        return time.perf_counter() - t0


def replace_block(readme, begin, end, text):
    pat = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
    if len(pat.findall(readme)) != 1:
        sys.exit(f"readme_timings: the README needs exactly one {begin} ... {end} block")
    return pat.sub(lambda _: begin + text + end, readme)


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
    text = (f"about {med['total']:.1f} s on {threads} cores ({', '.join(parts)}; medians "
            f"of {a.runs} runs by `scripts/readme_timings.py`, {datetime.date.today()}, load "
            f"average {load:.1f} at the start)")
    sweeps = sorted(one_sweep(a.binary) for _ in range(a.runs))
    sweep_text = (f"240 runs in {statistics.median(sweeps):.1f} s on {threads} cores, median "
                  f"of {a.runs} by `scripts/readme_timings.py`")
    if a.dry_run:
        print(text)
        print(sweep_text)
        return
    with open(a.readme, encoding="utf-8") as f:
        readme = f.read()
    readme = replace_block(readme, BEGIN, END, text)
    readme = replace_block(readme, SWEEP_BEGIN, SWEEP_END, sweep_text)
    with open(a.readme + ".tmp", "w", encoding="utf-8") as f:
        f.write(readme)
    os.replace(a.readme + ".tmp", a.readme)
    print(text)
    print(sweep_text)


if __name__ == "__main__":
    main()
