#!/usr/bin/python3
"""Open3D reference for bench_registration: the same model.ply / scan.ply through
Open3D's voxel_down_sample, registration_icp (point-to-plane) and compute_point_cloud_distance.

    SPRINGSCAN_BENCH_DATA_DIR=/tmp/fitbench ./build/bench/bench_registration   # writes the data
    /usr/bin/python3 bench/reference_open3d.py /tmp/fitbench [repetitions]
    # both in one run: the bench writes the data and is timed, then Open3D, then the ratio
    /usr/bin/python3 bench/reference_open3d.py /tmp/fitbench 5 ./build/bench/bench_registration

Open3D is Debian's python3-open3d (0.16.1 on Debian 12): `sudo apt-get install -y python3-open3d`.

Open3D gets the model normals from the file (as springscan does) and starts ICP from the
identity (springscan runs its PCA candidate search first, which Open3D has no equivalent of).
Prints the median wall time of each step and of the whole, and process CPU time."""
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import open3d as o3d


def run_once(model, scan, voxel, threshold):
    t0 = time.perf_counter()
    down = scan.voxel_down_sample(voxel)
    t1 = time.perf_counter()
    icp = o3d.pipelines.registration.registration_icp(
        down, model, threshold, np.eye(4),
        o3d.pipelines.registration.TransformationEstimationPointToPlane(),
        o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=50))
    t2 = time.perf_counter()
    moved = o3d.geometry.PointCloud(scan)
    moved.transform(icp.transformation)
    distances = np.asarray(moved.compute_point_cloud_distance(model))
    t3 = time.perf_counter()
    return (t1 - t0, t2 - t1, t3 - t2, t3 - t0), icp, distances


def springscan_global_stages(bench, folder, repetitions):
    """Runs BM_Inspection1MScan100kModel on 2 threads (it writes the data to `folder` first) and
    returns the medians of its wall time, process CPU and reduce + fit + deviation (the global
    stages), ms."""
    env = dict(os.environ, SPRINGSCAN_BENCH_DATA_DIR=folder)
    out = subprocess.run([bench, "--benchmark_filter=^BM_Inspection1MScan100kModel/2/",
                          f"--benchmark_repetitions={repetitions}", "--benchmark_format=json"],
                         env=env, check=True, capture_output=True, text=True).stdout
    runs = [b for b in json.loads(out)["benchmarks"] if b.get("run_type") == "iteration"]
    wall = statistics.median(b["real_time"] for b in runs)
    cpu = statistics.median(b["cpu_time"] for b in runs)
    stages = statistics.median(b["reduce_ms"] + b["fit_ms"] + b["deviation_ms"] for b in runs)
    return wall, cpu, stages


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else "/tmp/fitbench"
    repetitions = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    ours = None
    if len(sys.argv) > 3:
        os.makedirs(folder, exist_ok=True)
        ours = springscan_global_stages(sys.argv[3], folder, repetitions)
    model = o3d.io.read_point_cloud(folder + "/model.ply")
    scan = o3d.io.read_point_cloud(folder + "/scan.ply")
    if not model.has_normals():
        model.estimate_normals()
    extent = np.linalg.norm(scan.get_max_bound() - scan.get_min_bound())
    voxel = extent / 150.0  # springscan's automatic voxel (ReductionSettings)
    runs = []
    cpu0 = time.process_time()
    for _ in range(repetitions):
        times, icp, distances = run_once(model, scan, voxel, threshold=5.0)
        runs.append(times)
    cpu = (time.process_time() - cpu0) / repetitions
    names = ["voxel_down_sample", "registration_icp", "compute_point_cloud_distance", "total"]
    print(f"open3d {o3d.__version__}: scan {len(scan.points)} points, model {len(model.points)}, "
          f"voxel {voxel:.3f} mm, {len(runs)} runs")
    for k, name in enumerate(names):
        print(f"  {name:30s} median {1000 * statistics.median(r[k] for r in runs):8.1f} ms")
    print(f"  process CPU per run            {1000 * cpu:8.1f} ms")
    print(f"  icp fitness {icp.fitness:.4f} inlier_rmse {icp.inlier_rmse:.4f} mm, "
          f"p95 unsigned distance {np.percentile(distances, 95):.4f} mm")
    if ours:
        wall, cpu_ms, stages = ours
        total = 1000 * statistics.median(r[3] for r in runs)
        print(f"springscan BM_Inspection1MScan100kModel: median wall {wall:.1f} ms, process CPU "
              f"{cpu_ms:.1f} ms, reduce + fit + deviation {stages:.1f} ms")
        print(f"  Open3D / springscan: wall {total / wall:.2f}x, global stages "
              f"{total / stages:.2f}x, process CPU {1000 * cpu / cpu_ms:.2f}x")


if __name__ == "__main__":
    main()
