#!/usr/bin/env python3
"""Summary of scripts/ab-table.sh: per run, both builds' mean ATE over the samples and how often B
was better, then the geometric mean ratio B / A per group of runs.

Usage: ab_table.py OUT_DIR SAMPLE...   (reads OUT_DIR/a-SAMPLE.json and OUT_DIR/b-SAMPLE.json)
"""
import json
import math
import sys
from pathlib import Path


def load(path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as e:
        sys.exit(f"ab_table: cannot read {path}: {e}")


def group_of(run):
    if run.startswith("real-"):
        return "real drives" if run.count("-") == 2 else "real, degraded variants"
    return "plain street" if run.startswith("plain") else "stress scenarios"


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out, samples = Path(sys.argv[1]), sys.argv[2:]
    a = [load(out / f"a-{s}.json") for s in samples]
    b = [load(out / f"b-{s}.json") for s in samples]
    runs = sorted(set.intersection(*(set(t) for t in a + b)))
    if not runs:
        sys.exit("ab_table: no run is in every sample")
    print(f"ATE RMSE in m over {len(samples)} samples (ORBextractor.nFeatures {', '.join(samples)})\n")
    print("| run | A mean | B mean | B / A | B better in | A samples | B samples |")
    print("|---|---|---|---|---|---|---|")
    ratios = {}
    for run in runs:
        ate_a = [t[run]["ate_rmse_m"] for t in a]
        ate_b = [t[run]["ate_rmse_m"] for t in b]
        mean_a, mean_b = sum(ate_a) / len(ate_a), sum(ate_b) / len(ate_b)
        better = sum(1 for x, y in zip(ate_a, ate_b) if y < x)
        ratios.setdefault(group_of(run), []).append(mean_b / mean_a)
        print(f"| {run} | {mean_a:.3f} | {mean_b:.3f} | {mean_b / mean_a:.2f} | {better} of {len(samples)} | "
              f"{' '.join(f'{x:.3f}' for x in ate_a)} | {' '.join(f'{y:.3f}' for y in ate_b)} |")
    print("\n| group | runs | geometric mean of B / A |")
    print("|---|---|---|")
    for group, values in sorted(ratios.items()):
        geo = math.exp(sum(math.log(v) for v in values) / len(values))
        print(f"| {group} | {len(values)} | {geo:.3f} |")


if __name__ == "__main__":
    main()
