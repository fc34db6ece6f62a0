#!/usr/bin/env python3
"""Summary of scripts/ab-table.sh: per run, both builds' mean ATE over the samples and how often B
was better, then the geometric mean ratio B / A per group of runs, then per scenario run and build
its ATE as a multiple of the plain street's (same seed and frame count, as rgbl_accuracy_table pairs
them) over the samples: the ratio of the means and in how many samples the ratio passed 1.5 (issue
13's bar), which one table cannot tell from noise.

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


def scenario_seed(run):
    """("traffic", "1") for "traffic-s1"; None for a real drive."""
    if run.startswith("real-") or "-s" not in run:
        return None
    scenario, seed = run.rsplit("-s", 1)
    return (scenario, seed) if seed.isdigit() else None


def plain_ratios(tables, runs, bar=1.5):
    """Per scenario run (not the plain street): ratio of the mean ATEs to its plain street's, every
    sample's ratio, and how many exceed the bar."""
    plain = {}  # (seed, frames) -> run
    for run in runs:
        ss = scenario_seed(run)
        if ss and (ss[0] == "plain" or ss[0].startswith("plain@")):
            plain[(ss[1], tables[0][run]["frames"])] = run
    rows = []
    for run in runs:
        ss = scenario_seed(run)
        if not ss or ss[0] == "plain" or ss[0].startswith("plain@"):
            continue
        ref = plain.get((ss[1], tables[0][run]["frames"]))
        if ref is None:
            continue
        ate = [t[run]["ate_rmse_m"] for t in tables]
        ref_ate = [t[ref]["ate_rmse_m"] for t in tables]
        if min(ref_ate) <= 0.0:
            continue
        each = [x / y for x, y in zip(ate, ref_ate)]
        rows.append((run, ref, sum(ate) / sum(ref_ate), each, sum(1 for r in each if r > bar)))
    return rows


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out, samples = Path(sys.argv[1]), sys.argv[2:]
    a = [load(out / f"a-{s}.json") for s in samples]
    b = [load(out / f"b-{s}.json") for s in samples]
    runs = sorted(set.intersection(*(set(t) for t in a + b)))
    if not runs:
        sys.exit("ab_table: no run is in every sample")
    left_out = sorted(set.union(*(set(t) for t in a + b)) - set(runs))
    print(f"ATE RMSE in m over {len(samples)} samples (ORBextractor.nFeatures {', '.join(samples)})\n")
    if left_out:
        print(f"Left out, not in every sample of both sides: {', '.join(left_out)}\n")
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
    for name, tables in (("A", a), ("B", b)):
        rows = plain_ratios(tables, runs)
        if not rows:
            continue
        over = sum(1 for r in rows if r[2] > 1.5)
        print(f"\nBuild {name}: ATE as a multiple of the plain street's over the samples ({over} of {len(rows)} "
              "runs above 1.5 on the ratio of the means)\n")
        print("| run | plain | ratio of the mean ATEs | per sample | samples above 1.5 |")
        print("|---|---|---|---|---|")
        for run, ref, ratio, each, n_over in rows:
            flag = " !" if ratio > 1.5 else ""
            print(f"| {run} | {ref} | {ratio:.2f}{flag} | {' '.join(f'{r:.2f}' for r in each)} | {n_over} of {len(each)} |")


if __name__ == "__main__":
    main()
