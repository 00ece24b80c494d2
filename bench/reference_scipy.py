#!/usr/bin/python3
"""The same matching instances through scipy.optimize.linear_sum_assignment.

Runs `bench_matching --export=DIR` (our solver: writes the instances, our total costs and
median wall and process CPU times), then solves every instance with scipy on the dense squared
distance matrix, and prints one Markdown table row per instance: costs, their relative
difference (must be <= 1e-9), both times of both and the ratios. scipy's times exclude building
the matrix (shown in brackets). Exit status 1 if any cost differs.

    /usr/bin/python3 bench/reference_scipy.py build/bench/bench_matching

With --solve, the whole-command counterpart of `springscan match --model A --scan B --out C`
(bench/bench_cli_match.cpp times both as processes): reads two point files (x y z a line),
pairs them by linear_sum_assignment on the squared distances and writes C in the same CSV.

    /usr/bin/python3 bench/reference_scipy.py --solve A B C
"""
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist


def median_seconds(fn, repeats):
    """Median wall and median process CPU seconds of `fn`, and its last result."""
    wall, cpu = [], []
    result = None
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        result = fn()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return sorted(wall)[len(wall) // 2], sorted(cpu)[len(cpu) // 2], result


def solve(model_path, scan_path, out_path):
    """One run of what `springscan match` does, as a script: read, pair, write pairs.csv."""
    model = np.loadtxt(model_path)
    scan = np.loadtxt(scan_path)
    cost = cdist(model, scan, "sqeuclidean")
    rows, cols = linear_sum_assignment(cost)
    with open(out_path, "w") as out:
        out.write("model_index,scan_index,squared_distance_mm2\n")
        out.writelines(f"{r},{c},{cost[r, c]:.17g}\n" for r, c in zip(rows, cols))


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "--solve":
        solve(*sys.argv[2:])
        return
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    bench = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="springscan_matching_") as tmp:
        subprocess.run([bench, "--export=" + tmp], check=True)
        with open(os.path.join(tmp, "ours.txt")) as f:
            runs = [line.split() for line in f if line.strip()]
        print("| instance | solver | ours mm^2 | scipy mm^2 | rel. diff | ours ms wall / CPU | "
              "scipy ms wall / CPU (+ matrix) | scipy / ours wall, CPU |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        worst = 0.0
        for name, solver, our_cost, our_ms, our_cpu_ms in runs:
            model = np.loadtxt(os.path.join(tmp, name + "_model.txt"))
            scan = np.loadtxt(os.path.join(tmp, name + "_scan.txt"))
            rows, cols = (model, scan) if len(model) <= len(scan) else (scan, model)
            matrix_s, _, cost = median_seconds(lambda: cdist(rows, cols, "sqeuclidean"), 3)
            repeats = 5 if len(rows) <= 1500 else 1
            solve_s, solve_cpu_s, (r, c) = median_seconds(lambda: linear_sum_assignment(cost),
                                                          repeats)
            scipy_cost = float(cost[r, c].sum())
            ours = float(our_cost)
            rel = abs(ours - scipy_cost) / max(abs(scipy_cost), 1e-300)
            worst = max(worst, rel)
            wall, cpu = float(our_ms), float(our_cpu_ms)
            print(f"| {name} | {solver} | {ours:.9f} | {scipy_cost:.9f} | {rel:.1e} | "
                  f"{wall:.1f} / {cpu:.1f} | {1000 * solve_s:.1f} / {1000 * solve_cpu_s:.1f} "
                  f"(+{1000.0 * matrix_s:.1f}) | {1000 * solve_s / wall:.1f}x, "
                  f"{1000 * solve_cpu_s / cpu:.1f}x |")
        sys.exit(0 if worst <= 1e-9 else 1)


if __name__ == "__main__":
    main()
