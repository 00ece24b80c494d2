#!/usr/bin/python3
"""The same matching instances through scipy.optimize.linear_sum_assignment (issue 6).

Runs `bench_matching --export=DIR` (our solver: writes the instances, our total costs and
median wall times), then solves every instance with scipy on the dense squared
distance matrix, and prints one Markdown table row per instance: costs, their relative
difference (must be <= 1e-9) and the time ratio. Exit status 1 if any cost differs.

    /usr/bin/python3 bench/reference_scipy.py build/bench/bench_matching
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
    times = []
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return sorted(times)[len(times) // 2], result


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    bench = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="springscan_matching_") as tmp:
        subprocess.run([bench, "--export=" + tmp], check=True)
        with open(os.path.join(tmp, "ours.txt")) as f:
            runs = [line.split() for line in f if line.strip()]
        print("| instance | solver | ours mm^2 | scipy mm^2 | rel. diff | ours ms | "
              "scipy ms (+ matrix) | scipy / ours |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        worst = 0.0
        for name, solver, our_cost, our_ms in runs:
            model = np.loadtxt(os.path.join(tmp, name + "_model.txt"))
            scan = np.loadtxt(os.path.join(tmp, name + "_scan.txt"))
            rows, cols = (model, scan) if len(model) <= len(scan) else (scan, model)
            matrix_s, cost = median_seconds(lambda: cdist(rows, cols, "sqeuclidean"), 3)
            repeats = 5 if len(rows) <= 1500 else 1
            solve_s, (r, c) = median_seconds(lambda: linear_sum_assignment(cost), repeats)
            scipy_cost = float(cost[r, c].sum())
            ours = float(our_cost)
            rel = abs(ours - scipy_cost) / max(abs(scipy_cost), 1e-300)
            worst = max(worst, rel)
            scipy_ms = 1000.0 * solve_s
            print(f"| {name} | {solver} | {ours:.9f} | {scipy_cost:.9f} | {rel:.1e} | "
                  f"{float(our_ms):.1f} | {scipy_ms:.1f} (+{1000.0 * matrix_s:.1f}) | "
                  f"{scipy_ms / float(our_ms):.1f}x |")
        sys.exit(0 if worst <= 1e-9 else 1)


if __name__ == "__main__":
    main()
