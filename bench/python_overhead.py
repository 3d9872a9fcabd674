#!/usr/bin/env python3
"""What the Python module adds to a correlation: impactdic.correlate on two 1920x1440 arrays
against the same library call from C++ (docs/python.md, "Speed").

Both run pipeline CorrelateSceneInMemory on the same two decoded images with the same scene keys
(the defaults: subset 25, step 10; --threads 2): the C++ side is bench/python_overhead_benchmark,
kept running and asked for one correlation at a time (so neither side pays start-up); the Python
side is impactdic.correlate(reference, deformed, threads=2) on uint8 arrays, whose time includes
what the module adds (copying the arrays, the options, the result's arrays and summary). They take
turns, the order alternating, so that load from other jobs hits them alike; medians of --runs
runs each, after one warm-up call each; wall and CPU seconds (every thread's, user + system: less
sensitive to other jobs than the wall time). With --cli, the whole `impactdic correlate` process on the
PNG files takes a turn too, for scale (start-up, decoding, writing the .h5 file).

  /usr/bin/python3 bench/python_overhead.py --build build/bench [--runs 21] [--cli]

The pair (read with python3-pil) is the one of docs/dic_speed.md, written by bench/dic_benchmark
into /tmp/impactdic_dic_bench (--pair REF DEF for another). Speed figures belong in docs, never
in timed tests.
"""
import argparse
import os
import resource
import statistics
import subprocess
import sys
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default="build/bench",
                    help="a build with the benchmarks and the module (the bench preset)")
    ap.add_argument("--runs", type=int, default=21)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--cli", action="store_true", help="time the `impactdic correlate` process too")
    ap.add_argument("--pair", nargs=2, default=["/tmp/impactdic_dic_bench/frame_0.png",
                                                 "/tmp/impactdic_dic_bench/frame_1.png"])
    args = ap.parse_args()
    for p in args.pair:
        if not os.path.isfile(p):
            sys.exit(f"{p} does not exist: run bench/dic_benchmark once (it writes the pair), or "
                     "give --pair REF DEF")
    sys.path.insert(0, os.path.join(args.build, "python"))
    import numpy as np
    from PIL import Image  # python3-pil

    import impactdic

    arrays = [np.asarray(Image.open(p)) for p in args.pair]
    assert all(a.dtype == np.uint8 and a.ndim == 2 for a in arrays), "8-bit grey PNGs expected"
    program = os.path.join(args.build, "bench", "python_overhead_benchmark")
    cpp = subprocess.Popen([program, *args.pair, f"dic.threads={args.threads}"],
                           stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    cli = [os.path.join(args.build, "src", "cli", "impactdic"), "correlate", "--reference",
           args.pair[0], "--deformed", args.pair[1], "--threads", str(args.threads), "-o",
           "/dev/shm/impactdic_python_overhead.h5"]

    def cpu(who):
        usage = resource.getrusage(who)
        return usage.ru_utime + usage.ru_stime, usage.ru_minflt

    # Each returns (wall seconds, CPU seconds of every thread, minor page faults, subsets).
    def run_cpp():
        cpp.stdin.write("run\n")
        cpp.stdin.flush()
        seconds, cpu_s, faults, subsets = cpp.stdout.readline().split()
        return float(seconds), float(cpu_s), int(faults), int(subsets)

    def run_python():
        cpu0, faults0 = cpu(resource.RUSAGE_SELF)
        start = time.perf_counter()
        result = impactdic.correlate(*arrays, threads=args.threads)
        wall = time.perf_counter() - start
        cpu1, faults1 = cpu(resource.RUSAGE_SELF)
        return wall, cpu1 - cpu0, faults1 - faults0, result.x.size

    def run_cli():
        cpu0, faults0 = cpu(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        subprocess.run(cli, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wall = time.perf_counter() - start
        cpu1, faults1 = cpu(resource.RUSAGE_CHILDREN)
        return wall, cpu1 - cpu0, faults1 - faults0, None

    contenders = {"C++ library call": run_cpp, "Python correlate(arrays)": run_python}
    if args.cli:
        contenders["impactdic correlate process"] = run_cli
    walls = {name: [] for name in contenders}
    cpus = {name: [] for name in contenders}
    faults = {name: [] for name in contenders}
    subsets = {}
    for run in contenders.values():  # Warm-up: page cache, TBB threads, allocations.
        run()
    load = [os.getloadavg()[0]]
    for k in range(args.runs):
        order = list(contenders) if k % 2 == 0 else list(reversed(contenders))
        for name in order:
            wall, cpu_s, fault_count, n = contenders[name]()
            walls[name].append(wall)
            cpus[name].append(cpu_s)
            faults[name].append(fault_count)
            if n is not None:
                subsets[name] = n
        load.append(os.getloadavg()[0])
    cpp.stdin.close()
    cpp.wait()
    if len(set(subsets.values())) != 1:
        sys.exit(f"the calls correlated different grids: {subsets}")

    print(f"impactdic {impactdic.__version__}; {args.runs} runs each, alternating; "
          f"{os.cpu_count()} CPUs, load average (1 min) {min(load):.2f}-{max(load):.2f}; "
          f"{arrays[0].shape[1]}x{arrays[0].shape[0]} pair {args.pair[0]} {args.pair[1]}, "
          f"{next(iter(subsets.values()))} subsets (subset 25, step 10), {args.threads} threads")
    for name in contenders:
        w, c = walls[name], cpus[name]
        print(f"  {name:28s} wall median {statistics.median(w):.4f} s (min {min(w):.4f}, max "
              f"{max(w):.4f}); CPU median {statistics.median(c):.4f} s; "
              f"{statistics.median(faults[name]):.0f} page faults")
    py, cc = "Python correlate(arrays)", "C++ library call"
    for what, values in (("wall", walls), ("CPU", cpus)):
        ratio = statistics.median(values[py]) / statistics.median(values[cc])
        # The turns in pairs: the median of the ratios of one turn each, back to back.
        paired = statistics.median(p / c for p, c in zip(values[py], values[cc]))
        print(f"  Python / C++ {what}: {ratio:.4f} of the medians ({100 * (ratio - 1):+.1f} %), "
              f"{paired:.4f} median of the paired turns ({100 * (paired - 1):+.1f} %)")

if __name__ == "__main__":
    main()
