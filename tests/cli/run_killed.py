#!/usr/bin/env python3
"""Soak: `rgbl run` into one --out folder, killed again and again at random points (SIGINT, SIGTERM,
SIGKILL; inline and --threaded). After every kill the folder holds only complete, consistent files:

- SIGINT/SIGTERM: exit 0 (done before the signal), 128 + signal with the partial outputs, or death by
  the signal before rgbl installed its handler (nothing written yet); never a temporary left behind;
- SIGKILL: whatever is there is whole (write_atomically): trajectories of 12 numbers a row and as
  many rows as summary.json's frames, a JSON that parses, a closed SVG, a PLY with its header;
- a run after all that succeeds and leaves no temporary of the killed runs.

Usage: run_killed.py RGBL RGBL_SIM WORK_DIR [KILLS]. The kill times are drawn from a fixed seed; where a
kill lands depends on the machine, and every check holds wherever it lands.
"""
import json
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

RGBL, SIM, WORK = sys.argv[1], sys.argv[2], Path(sys.argv[3])
KILLS = int(sys.argv[4]) if len(sys.argv) > 4 else 18
OUTPUTS = ["trajectory_kitti.txt", "trajectory_tum.txt", "ground_truth_kitti.txt", "timing.csv", "summary.json",
           "trajectory.svg", "map.ply"]


def fail(message):
    print(f"FAILED: {message}")
    sys.exit(1)


def rows(path, fields):
    lines = [line for line in path.read_text().splitlines() if line and not line.startswith("#")]
    for n, line in enumerate(lines, 1):
        if len(line.split()) != fields:
            fail(f"{path.name}:{n}: {len(line.split())} fields, expected {fields} (a half-written file?)")
    return len(lines)


def check_folder(out, allow_temporaries):
    temporaries = sorted(p.name for p in out.glob("*.part"))
    if temporaries and not allow_temporaries:
        fail(f"temporary files left: {temporaries}")
    present = {name for name in OUTPUTS if (out / name).exists()}
    frames = None
    if "summary.json" in present:
        summary = json.loads((out / "summary.json").read_text())  # raises on a half-written file
        frames = summary["frames"]
        if summary.get("partial", False) != (frames < summary["frames_planned"]):
            fail(f"summary.json: partial {summary.get('partial')} but {frames} of {summary['frames_planned']} frames")
    counts = {}
    for name, fields in (("trajectory_kitti.txt", 12), ("ground_truth_kitti.txt", 12), ("trajectory_tum.txt", 8)):
        if name in present:
            counts[name] = rows(out / name, fields)
    if "timing.csv" in present:
        lines = (out / "timing.csv").read_text().splitlines()
        if not lines or not lines[0].startswith("frame,"):
            fail("timing.csv without its header")
        width = len(lines[0].split(","))
        if any(len(line.split(",")) != width for line in lines[1:]):
            fail("timing.csv: a row of another width (a half-written file?)")
        counts["timing.csv"] = len(lines) - 1
    if frames is not None:
        for name, n in counts.items():
            if n != frames:
                fail(f"{name} has {n} rows, summary.json says {frames} frames (files of two runs mixed?)")
    if "trajectory.svg" in present and not (out / "trajectory.svg").read_text().rstrip().endswith("</svg>"):
        fail("trajectory.svg is not closed")
    if "map.ply" in present:
        head = (out / "map.ply").read_bytes()[:4096]
        if not head.startswith(b"ply\n") or b"end_header\n" not in head:
            fail("map.ply without its header")
    return present, frames, temporaries


def main():
    shutil.rmtree(WORK, ignore_errors=True)
    WORK.mkdir(parents=True)
    subprocess.run([SIM, "--out", str(WORK / "data"), "--frames", "60", "--cameras", "0", "--no-depth", "--quiet"],
                   check=True, stdout=subprocess.DEVNULL)
    sequence = str(WORK / "data" / "sequences" / "00")
    out = WORK / "out"

    def command(threaded):
        return [RGBL, "--quiet", "run", sequence, "--out", str(out)] + (["--threaded"] if threaded else [])

    start = time.monotonic()
    subprocess.run(command(False), check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    duration = time.monotonic() - start
    check_folder(out, allow_temporaries=False)
    print(f"a whole run takes {duration:.2f} s; {KILLS} kills in the first {1.1 * duration:.2f} s")

    rng = random.Random(29)
    signals = [signal.SIGINT, signal.SIGTERM, signal.SIGKILL]
    outcomes = {}
    for k in range(KILLS):
        sig = signals[k % 3]
        threaded = (k // 3) % 2 == 1
        delay = rng.uniform(0.0, 1.1 * duration)
        process = subprocess.Popen(command(threaded), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        time.sleep(delay)
        process.send_signal(sig)
        _, err = process.communicate(timeout=120)
        rc = process.returncode
        allowed = {0, -sig} if sig == signal.SIGKILL else {0, 128 + sig, -sig}
        if rc not in allowed:
            fail(f"kill {k}: {sig.name} after {delay:.2f} s: exit {rc}, expected one of {sorted(allowed)}\n"
                 f"{err.decode(errors='replace')}")
        present, frames, temporaries = check_folder(out, allow_temporaries=sig == signal.SIGKILL)
        if rc == 128 + sig and (frames is None or len(present) < 6):
            fail(f"kill {k}: exit {rc} (interrupted) but the partial outputs are missing: {sorted(present)}")
        outcome = {0: "done", 128 + sig: "partial outputs", -sig: "killed"}[rc]
        outcomes[outcome] = outcomes.get(outcome, 0) + 1
        print(f"kill {k:2d}: {sig.name:7s} after {delay:.2f} s{' (--threaded)' if threaded else '':13s} -> exit {rc:4d}, "
              f"{outcome}; {frames if frames is not None else '-'} frames in summary.json, "
              f"{len(present)} outputs, {len(temporaries)} temporaries")
    # what a SIGKILL while writing leaves (rarely hit above: writing takes milliseconds), and a file of
    # the user's that only looks like one
    (out / "summary.json.x7Kq2P.part").write_text('{"frames": ')
    (out / "notes.part").write_text("mine")
    subprocess.run(command(False), check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    if not (out / "notes.part").exists():
        fail("the run removed notes.part, which is not one of its temporaries")
    (out / "notes.part").unlink()
    present, frames, _ = check_folder(out, allow_temporaries=False)
    if frames != 60 or len(present) != len(OUTPUTS):
        fail(f"the run after the kills: {frames} frames, outputs {sorted(present)}")
    print(f"outcomes: {outcomes}; the run after them is whole and left no temporary")


main()
