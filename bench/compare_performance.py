#!/usr/bin/env python3
"""Runs the whole-analysis benchmarks and compares each stage with the figures committed in
docs/performance.md (the table between the "perf-compare figures" markers, issue 37).

    python3 bench/compare_performance.py            # before landing: medians of 5, 1M points
    python3 bench/compare_performance.py --quick    # CI: a 20,000-point hat, one run, no verdict

Names every stage more than 15 % (and 1 ms) slower than its committed median and exits 1 when
there is one; exit 0 otherwise. With --quick the scan is too small to compare with the 1M
figures: the table is printed, the slower stages named, and the exit status is 0 (CI checks that
the benchmark and this script run). Run it on an otherwise idle machine, or compare A/B: on the
shared 2-core machine wall times vary by +-20 % with the load (uptime is printed).
"""
import argparse
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BEGIN = "<!-- perf-compare figures: begin -->"
END = "<!-- perf-compare figures: end -->"
# benchmark name prefix -> program in build/bench/
PROGRAMS = {"BM_AnalysisHat1M": "bench_analysis", "BM_InspectionSidePanel1M": "bench_production"}
SLOWER = 1.15
SLACK_MS = 1.0


def committed_figures(doc):
    """{benchmark: {counter: ms}} from the marked table of docs/performance.md."""
    text = open(doc, encoding="utf-8").read()
    if BEGIN not in text or END not in text:
        sys.exit(f"compare_performance: no perf-compare table in {doc}")
    rows = [r.strip() for r in text.split(BEGIN)[1].split(END)[0].splitlines()]
    rows = [r for r in rows if r.startswith("|") and not r.startswith("| ---")]
    header = [c.strip() for c in rows[0].strip("|").split("|")]
    figures = {}
    for row in rows[1:]:
        cells = [c.strip() for c in row.strip("|").split("|")]
        name = cells[0].strip("`")
        figures[name] = {h: float(c.replace(",", "")) for h, c in zip(header[1:], cells[1:]) if c}
    return header[1:], figures


def run(program, names, quick, repetitions):
    """{benchmark: {counter: median}} of one benchmark program."""
    env = dict(os.environ)
    args = [program, "--benchmark_filter=^(" + "|".join(re.escape(n) for n in names) + ")(/|$)",
            "--benchmark_format=json", "--benchmark_min_time=0.001"]
    if quick:
        env["SPRINGSCAN_BENCH_POINTS"] = "20000"
    medians = not quick and repetitions > 1
    if medians:
        args += [f"--benchmark_repetitions={repetitions}", "--benchmark_report_aggregates_only=true"]
    out = subprocess.run(args, env=env, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        sys.exit(f"compare_performance: {program} failed ({out.returncode}): {out.stderr[-2000:]}")
    results = {}
    for b in json.loads(out.stdout)["benchmarks"]:
        if b.get("error_occurred"):
            sys.exit(f"compare_performance: {b['name']}: {b.get('error_message')}")
        if medians and b.get("aggregate_name") != "median":
            continue
        name = re.sub(r"(/process_time)?(/real_time)?$", "", b.get("run_name", b["name"]))
        results[name] = b
    return results


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="CI: a small scan, one run, no verdict")
    parser.add_argument("--build", default=os.path.join(ROOT, "build"), help="the Release build")
    parser.add_argument("--doc", default=os.path.join(ROOT, "docs", "performance.md"))
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--filter", default="", help="only benchmarks whose name contains this")
    args = parser.parse_args()
    counters, committed = committed_figures(args.doc)
    names = [n for n in committed if args.filter in n]
    if args.quick:  # the side panel's CAD and scan take longer than CI should spend
        names = [n for n in names if n.startswith("BM_AnalysisHat1M")]
    print(f"load average {os.getloadavg()[0]:.2f}; "
          + ("quick: 20,000 points, one run, not compared for a verdict" if args.quick
             else f"medians of {args.repetitions}"))
    measured = {}
    for prefix, program in PROGRAMS.items():
        wanted = [n for n in names if n.startswith(prefix)]
        if wanted:
            measured.update(run(os.path.join(args.build, "bench", program), wanted, args.quick,
                                args.repetitions))
    slower = []
    print(f"{'benchmark':34} {'stage':14} {'committed':>10} {'now':>10} {'ratio':>6}")
    for name in names:
        if name not in measured:
            sys.exit(f"compare_performance: {name} did not run")
        for counter in counters:
            if counter not in committed[name]:
                continue
            before, now = committed[name][counter], float(measured[name].get(counter, "nan"))
            ratio = now / before if before > 0 else float("inf")
            flag = ""
            if now > SLOWER * before and now - before > SLACK_MS:
                flag = "  SLOWER"
                slower.append(f"{name} {counter}")
            print(f"{name:34} {counter:14} {before:10.1f} {now:10.1f} {ratio:6.2f}{flag}")
    if slower:
        print("more than 15 % slower: " + ", ".join(slower))
    else:
        print("no stage more than 15 % slower")
    return 0 if args.quick or not slower else 1


if __name__ == "__main__":
    sys.exit(main())
