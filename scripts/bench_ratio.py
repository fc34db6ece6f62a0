#!/usr/bin/env python3
"""Same-run ratios of Google Benchmark pairs, robust to a noisy machine.

Runs rgbl_bench with many short repetitions in random interleaving (so both sides of a pair see the
same machine), then prints, per benchmark, the minimum and median time over the repetitions (CPU time; wall time for /real_time runs) and,
for each PAIR "ours:reference", reference / ours for both. The minimum is the least-disturbed run of
each side; on a quiet machine both ratios agree.

  scripts/bench_ratio.py [--bench build/release/bin/rgbl_bench] [--repetitions 40]
                         [--filter 'orb/(rgbl|opencv)$'] [--pair orb/rgbl:orb/opencv ...]
"""
import argparse
import json
import statistics
import subprocess
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bench", default="build/release/bin/rgbl_bench")
    parser.add_argument("--repetitions", type=int, default=40)
    parser.add_argument("--min-time", default="0.05")
    parser.add_argument("--filter", default="orb/(rgbl|opencv)$")
    parser.add_argument("--pair", action="append", default=None,
                        help="ours:reference run names (default orb/rgbl:orb/opencv)")
    args = parser.parse_args()
    pairs = args.pair or ["orb/rgbl:orb/opencv"]
    command = [args.bench, f"--benchmark_filter={args.filter}", f"--benchmark_repetitions={args.repetitions}",
               "--benchmark_enable_random_interleaving=true", f"--benchmark_min_time={args.min_time}",
               "--benchmark_format=json"]
    try:
        out = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError) as error:
        sys.exit(f"bench_ratio: {' '.join(command)} failed: {error}")
    times = {}
    for run in json.loads(out)["benchmarks"]:
        if run.get("run_type") == "iteration":
            # wall time for benchmarks timed so (UseRealTime: several threads), else CPU time
            key = "real_time" if run["run_name"].endswith("/real_time") else "cpu_time"
            times.setdefault(run["run_name"], []).append(run[key])
    for name, values in sorted(times.items()):
        print(f"{name}: min {min(values):.3f}  median {statistics.median(values):.3f} ms  ({len(values)} repetitions)")
    for pair in pairs:
        ours, reference = pair.split(":")
        if ours not in times or reference not in times:
            sys.exit(f"bench_ratio: pair {pair}: no runs named {ours if ours not in times else reference}")
        a, b = times[ours], times[reference]
        print(f"{reference} / {ours}: {min(b) / min(a):.2f}x by minimum, "
              f"{statistics.median(b) / statistics.median(a):.2f}x by median")


if __name__ == "__main__":
    main()
