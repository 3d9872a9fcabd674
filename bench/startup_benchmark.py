#!/usr/bin/env python3
"""Process start-up of impactdic, and a one-shot `impactdic correlate` of a 1920x1440 pair.

Times whole processes (wall clock, median / min / max of --runs runs, the binaries taking turns so
that load from other jobs hits them alike): `impactdic version` (start-up and exit only) and
`impactdic correlate` of the pair of docs/dic_speed.md ("Speed"; written by bench/dic_benchmark into
/tmp/impactdic_dic_bench). Also prints, per binary, how many shared libraries the loader maps
(ldd) and which OpenCV libraries the correlate run loads (LD_DEBUG=files).

  bench/startup_benchmark.py --impactdic build/release/src/cli/impactdic \\
      [--impactdic /path/to/older/impactdic] [--runs 15] [--threads 2] [--pair REF DEF]

Speed figures belong here, not in timed unit tests (tests/cli/startup_test.cc checks only which
libraries the correlation path loads).
"""
import argparse
import os
import resource
import statistics
import subprocess
import sys
import time


def timed(cmd, env=None):
    """Wall and CPU (user + sys of the child) seconds of one run; raises if it fails."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    result = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({result.returncode}): {result.stderr.decode()[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def libraries(binary):
    out = subprocess.run(["ldd", binary], capture_output=True, text=True).stdout
    return len([line for line in out.splitlines() if line.strip()])


def opencv_loaded(cmd):
    """The OpenCV (and plugin) libraries the run maps, from the dynamic loader's trace."""
    env = dict(os.environ, LD_DEBUG="files")
    err = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env).stderr
    names = set()
    for line in err.decode(errors="replace").splitlines():
        if "file=" in line:
            name = line.split("file=")[1].split()[0].split("/")[-1]
            if "opencv" in name:
                names.add(name)
    return sorted(names)


def summary(values):
    return (f"{statistics.median(values):7.4f} s (min {min(values):.4f}, max {max(values):.4f})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--impactdic", action="append", required=True,
                    help="impactdic binary (repeat to compare several)")
    ap.add_argument("--runs", type=int, default=15)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--pair", nargs=2, default=["/tmp/impactdic_dic_bench/frame_0.png",
                                                 "/tmp/impactdic_dic_bench/frame_1.png"])
    ap.add_argument("--out", default="/dev/shm/impactdic_startup_pair.h5",
                    help="correlate output (on tmpfs by default: the disk is not timed)")
    args = ap.parse_args()
    for p in args.pair:
        if not os.path.isfile(p):
            sys.exit(f"{p} does not exist: run bench/dic_benchmark once (it writes the pair), or "
                     "give --pair REF DEF")

    def correlate(binary):
        return [binary, "-q", "correlate", "--reference", args.pair[0], "--deformed",
                args.pair[1], "--subset", "25", "--step", "10", "--threads", str(args.threads),
                "-o", args.out]

    times = {b: {"version": [], "version_cpu": [], "correlate": [], "correlate_cpu": []}
             for b in args.impactdic}
    for b in args.impactdic:  # warm the page cache
        timed([b, "version"])
        timed(correlate(b))
    for _ in range(args.runs):
        for b in args.impactdic:
            w, c = timed([b, "version"])
            times[b]["version"].append(w)
            times[b]["version_cpu"].append(c)
            w, c = timed(correlate(b))
            times[b]["correlate"].append(w)
            times[b]["correlate_cpu"].append(c)

    print(f"{args.runs} runs each, {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.2f}; pair {args.pair[0]} {args.pair[1]}, subset 25, step 10, "
          f"{args.threads} threads")
    for b in args.impactdic:
        t = times[b]
        print(f"\n{b}")
        print(f"  shared libraries (ldd):     {libraries(b)}")
        print(f"  OpenCV libraries loaded by correlate: {', '.join(opencv_loaded(correlate(b)))}")
        print(f"  version   wall {summary(t['version'])}; CPU median "
              f"{statistics.median(t['version_cpu']):.4f} s")
        print(f"  correlate wall {summary(t['correlate'])}; CPU median "
              f"{statistics.median(t['correlate_cpu']):.4f} s")
    if len(args.impactdic) == 2:
        a, b = args.impactdic
        for key in ("version", "correlate"):
            ma, mb = statistics.median(times[a][key]), statistics.median(times[b][key])
            print(f"\n{key}: median {ma:.4f} s -> {mb:.4f} s ({ma / mb:.2f}x as fast, "
                  f"difference {ma - mb:.4f} s)")

if __name__ == "__main__":
    main()
