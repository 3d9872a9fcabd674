#!/usr/bin/env python3
"""The whole `impactdic correlate` process on the 1920x1440 benchmark pair, against an anchor.

Times whole processes (start-up, PNG decoding, correlation, HDF5 output; wall clock, median / min /
max of --runs runs, the programs taking turns so that load from other jobs hits them alike):
`impactdic correlate --reference frame_0.png --deformed frame_1.png --subset 25 --step 10
--threads 2 -o /dev/shm/...h5` for each --impactdic binary, and, with --anchor, another DIC
program on the same pair. Prints the phases impactdic reports (coefficients, reference, initial
guess, IC-GN; the rest of the wall time is start-up, reading and writing) and, per binary, the
anchor's median over its own. The pair is the one of docs/dic_speed.md ("Speed"), written by
bench/dic_benchmark into /tmp/impactdic_dic_bench.

  bench/pair_benchmark.py --impactdic build/release/src/cli/impactdic \\
      [--impactdic /path/to/older/impactdic] [--anchor 'CMD {ref} {def}'] [--runs 15]

The speed anchor is OpenCorr (https://github.com/vincentjzy/OpenCorr; not vendored, not a
dependency): FFT-CC initial guess + first-order IC-GN (bicubic B-spline), subset 25 (radius 12),
POIs every 10 px over the image less 16 px of border, 2 OpenMP threads, images read with its own
OpenCV loader. Build its example `test_2d_dic_fftcc_icgn1` (FFTW 3, Eigen 3, OpenCV) with
`g++ -O3 -march=native -fopenmp`, edited to take the two image paths from argv, use 2 threads and
skip its CSV output, and give it as --anchor '/path/to/fftcc_icgn1 {ref} {def}'. Speed figures
belong here and in docs/dic.md, never in timed unit tests.

Where the anchor cannot run (it is not installed on the benchmark VM, and the VM's speed drifts
through the day by up to 2x, so a figure from another run does not compare), --anchor-via
BINARY RATIO estimates it from a program measured against it once: BINARY is timed in the same
runs as the others and RATIO times its median stands for the anchor's (assuming both slow down
alike with the machine). Issue 38 timed OpenCorr at 1.00 s and impactdic at main ffeac34 at
0.43 s in one run: build that commit's `impactdic`

  git worktree add /tmp/ffeac34 ffeac34 && cd /tmp/ffeac34 && \\
      cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release && cmake --build build --target impactdic

and give --anchor-via /tmp/ffeac34/build/src/cli/impactdic 2.326.
"""
import argparse
import os
import re
import shlex
import statistics
import subprocess
import sys
import time


def timed(cmd):
    """Wall seconds of one run and its stderr; exits if it fails."""
    t0 = time.perf_counter()
    result = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    wall = time.perf_counter() - t0
    if result.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({result.returncode}): {result.stderr.decode()[-2000:]}")
    return wall, result.stderr.decode(errors="replace")


PHASES = ("coefficients", "reference", "initial guess", "IC-GN")


def phases(log):
    """The phase times of impactdic's summary line 'time: coefficients X s, reference Y s, ...'."""
    out = {}
    for name in PHASES:
        m = re.search(re.escape(name) + r" ([0-9.]+) s", log)
        if m:
            out[name] = float(m.group(1))
    return out


def summary(values):
    return f"{statistics.median(values):.4f} s (min {min(values):.4f}, max {max(values):.4f})"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--impactdic", action="append", required=True,
                    help="impactdic binary (repeat to compare several)")
    ap.add_argument("--anchor", help="command line of the anchor, with {ref} and {def}")
    ap.add_argument("--anchor-via", nargs=2, metavar=("BINARY", "RATIO"),
                    help="estimate the anchor as RATIO x the median of this impactdic binary, "
                         "timed in the same runs")
    ap.add_argument("--runs", type=int, default=15)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--pair", nargs=2, default=["/tmp/impactdic_dic_bench/frame_0.png",
                                                 "/tmp/impactdic_dic_bench/frame_1.png"])
    ap.add_argument("--out", default="/dev/shm/impactdic_pair_benchmark.h5",
                    help="correlate output (on tmpfs by default: the disk is not timed)")
    args = ap.parse_args()
    if args.anchor and args.anchor_via:
        sys.exit("--anchor and --anchor-via: give one (the anchor itself, or its estimate)")
    via_ratio = None
    if args.anchor_via:
        try:
            via_ratio = float(args.anchor_via[1])
        except ValueError:
            via_ratio = -1.0
        if not via_ratio > 0:
            sys.exit(f"--anchor-via RATIO: a number > 0 expected, got {args.anchor_via[1]}")
    for p in args.pair:
        if not os.path.isfile(p):
            sys.exit(f"{p} does not exist: run bench/dic_benchmark once (it writes the pair), or "
                     "give --pair REF DEF")

    def correlate(binary):
        return [binary, "correlate", "--reference", args.pair[0], "--deformed", args.pair[1],
                "--subset", "25", "--step", "10", "--threads", str(args.threads), "-o", args.out]

    programs = {b: correlate(b) for b in args.impactdic}
    if args.anchor:
        programs["anchor"] = shlex.split(args.anchor.format(ref=args.pair[0], **{"def": args.pair[1]}))
    if args.anchor_via:
        programs["anchor proxy"] = correlate(args.anchor_via[0])
    walls = {name: [] for name in programs}
    split = {b: {p: [] for p in PHASES} for b in args.impactdic}
    load = []
    for cmd in programs.values():  # warm the page cache
        timed(cmd)
    for _ in range(args.runs):
        load.append(os.getloadavg()[0])
        for name, cmd in programs.items():
            wall, log = timed(cmd)
            walls[name].append(wall)
            if name in split:
                for p, v in phases(log).items():
                    split[name][p].append(v)

    print(f"{args.runs} runs each, {os.cpu_count()} CPUs, load average {min(load):.2f}-"
          f"{max(load):.2f} (1 min); pair {args.pair[0]} {args.pair[1]}, subset 25, step 10, "
          f"{args.threads} threads")
    anchor = None
    if args.anchor:
        anchor = statistics.median(walls["anchor"])
    elif args.anchor_via:
        anchor = via_ratio * statistics.median(walls["anchor proxy"])
    for name in programs:
        shown = f"{name} ({args.anchor_via[0]})" if name == "anchor proxy" else name
        print(f"\n{shown}\n  whole process wall {summary(walls[name])}")
        if name == "anchor proxy":
            print(f"  the anchor estimated: {via_ratio:g} x {statistics.median(walls[name]):.4f} s "
                  f"= {anchor:.4f} s")
        if name in split:
            parts = ", ".join(f"{p} {statistics.median(v):.4f}" for p, v in split[name].items() if v)
            print(f"  phases (median, s): {parts}")
            if anchor is not None:
                ratio = anchor / statistics.median(walls[name])
                print(f"  anchor{' (estimated)' if args.anchor_via else ''} / this: {ratio:.2f}x")
    if len(args.impactdic) == 2:
        a, b = args.impactdic
        ma, mb = statistics.median(walls[a]), statistics.median(walls[b])
        print(f"\nmedian {ma:.4f} s -> {mb:.4f} s ({ma / mb:.2f}x as fast)")


if __name__ == "__main__":
    main()
