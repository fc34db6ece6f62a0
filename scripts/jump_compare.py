#!/usr/bin/env python3
"""Two tables of scripts/jump-table.sh compared pair by pair (drive and gap): every pair where a
column moved, not only the large moves. A change to the scan search once looked like "every pair
identical but one" from the bridged ATE alone, while a bridge was refused in two other pairs and a
run without bridging failed (docs/accuracy.md, "The ring plane fit on by default").

Usage: jump_compare.py A B [--tolerance M]   (default 0.005 m)

Per changed pair: the bridged ATE, the ATE without bridging and the bridge (its frames, or "-").
Then per column the geometric mean of B / A over the pairs in both tables and the runs over 0.5 m.
"""
import argparse
import math
import re
import sys

LINE = re.compile(r"(?P<dataset>\S+) gap (?P<gap>\S+) \| ATE without gap (?P<gapless>[\d.]+) m \| "
                  r"bridging: ATE (?P<bridged>[\d.]+) m(?P<bridging>[^|]*)\| without: ATE (?P<without>[\d.]+) m")
BRIDGE = re.compile(r"bridged (\d+) with (\d+)")


def name_of(dataset):
    # a scenario's cache folder (name-sSEED-fFRAMES-KEY/sequences/00) or a real drive's folder
    parts = dataset.rstrip("/").split("/")
    if len(parts) >= 3 and parts[-2] == "sequences" and "-s" in parts[-3]:
        return re.sub(r"-[0-9a-f]{12}$", "", parts[-3])
    return parts[-1] if parts[-2] != "sequences" else "odometry-" + parts[-1]


def load(path):
    table = {}
    try:
        f = open(path, encoding="utf-8")
    except OSError as e:
        sys.exit(f"{path}: cannot read ({e.strerror})")
    with f:
        for number, line in enumerate(f, 1):
            if "FAILED" in line:
                sys.exit(f"{path}:{number}: a failed run ({line.strip()}); rerun it before comparing")
            m = LINE.match(line)
            if not m:
                continue
            bridge = BRIDGE.search(m.group("bridging"))
            table[(name_of(m.group("dataset")), m.group("gap"))] = {
                "bridged": float(m.group("bridged")),
                "without": float(m.group("without")),
                "bridge": f"{bridge.group(1)} with {bridge.group(2)}" if bridge else "-",
            }
    if not table:
        sys.exit(f"{path}: no rows of scripts/jump-table.sh")
    return table


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("a")
    parser.add_argument("b")
    parser.add_argument("--tolerance", type=float, default=0.005, help="m; smaller moves count as unchanged")
    args = parser.parse_args()
    a, b = load(args.a), load(args.b)
    common = [k for k in a if k in b]
    for side, table, other in (("A", a, b), ("B", b, a)):
        missing = [k for k in table if k not in other]
        if missing:
            print(f"only in {side}: " + ", ".join(f"{n} gap {g}" for n, g in missing))
    changed = 0
    for key in common:
        x, y = a[key], b[key]
        moved = [c for c in ("bridged", "without") if abs(x[c] - y[c]) > args.tolerance]
        if not moved and x["bridge"] == y["bridge"]:
            continue
        changed += 1
        print(f"{key[0]} gap {key[1]}: bridged {x['bridged']:.3f} -> {y['bridged']:.3f} m, "
              f"without {x['without']:.3f} -> {y['without']:.3f} m, bridge {x['bridge']} -> {y['bridge']}")
    print(f"{changed} of {len(common)} pairs changed (tolerance {args.tolerance} m)")
    for column in ("bridged", "without"):
        ratios = [b[k][column] / a[k][column] for k in common if a[k][column] > 0 and b[k][column] > 0]
        mean = math.exp(sum(math.log(r) for r in ratios) / len(ratios)) if ratios else float("nan")
        over_a = sum(a[k][column] > 0.5 for k in common)
        over_b = sum(b[k][column] > 0.5 for k in common)
        print(f"{column}: geometric mean B / A {mean:.3f}, runs over 0.5 m {over_a} -> {over_b}")
    print(f"bridges made: {sum(a[k]['bridge'] != '-' for k in common)} -> {sum(b[k]['bridge'] != '-' for k in common)}")


if __name__ == "__main__":
    main()
