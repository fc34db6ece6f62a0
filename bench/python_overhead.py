#!/usr/bin/env python3
"""Python's overhead per frame over the C++ call of System.track, both measured in the same run.

Every frame is loaded into memory first (so no file IO is timed), then tracked through the Python
binding. Per frame this measures:
  python_ms  time.perf_counter_ns() around `system.track(...)` in Python;
  cpp_ms     TrackResult.timing.total_ms, which System::track measures around its own body in C++.
Their difference is what the binding adds: argument conversion (numpy -> cv::Mat header, scan view),
releasing and re-taking the GIL, and converting the TrackResult back. Each pass uses a fresh System from
Pipeline.make_system() (the System `rgbl run` tracks with), so every pass tracks the same frames.

    PYTHONPATH=build/release/python python3 bench/python_overhead.py [dataset] [--passes 5] [--frames N]

Without a dataset argument it uses the KITTI excerpt (../shared/data/kitti/odometry/sequences/04 or
$RGBL_DATA_DIR) when present, else renders a synthetic street into a temporary folder.
"""

import argparse
import os
import pathlib
import statistics
import sys
import tempfile
import time

import rgbl


def default_dataset(tmp: str) -> pathlib.Path:
    root = os.environ.get("RGBL_DATA_DIR") or pathlib.Path(__file__).resolve().parents[2] / "shared" / "data"
    seq = pathlib.Path(root) / "kitti" / "odometry" / "sequences" / "04"
    if seq.exists():
        return seq
    print("no KITTI excerpt: tracking a synthetic street", file=sys.stderr)
    return pathlib.Path(rgbl.write_synthetic_kitti(tmp, frames=50, path="curve").sequence_dir)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", nargs="?")
    parser.add_argument("--passes", type=int, default=5)
    parser.add_argument("--frames", type=int, default=0, help="0 = all")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        dataset = pathlib.Path(args.dataset) if args.dataset else default_dataset(tmp)
        pipeline = rgbl.Pipeline(dataset, frames=args.frames)
        cam = pipeline.camera
        frames = [pipeline.sequence.load(pipeline.frame_index(i)) for i in range(pipeline.frame_count)]
        inputs = [(f.images[cam], f.scan, f.index, f.timestamp, f.images[cam + 1]) for f in frames]

        overhead_ms, python_ms, cpp_ms = [], [], []
        for _ in range(args.passes):
            system = pipeline.make_system()
            for image, scan, index, timestamp, right in inputs:
                start = time.perf_counter_ns()
                result = system.track(image, scan, index=index, timestamp=timestamp, image_right=right)
                elapsed = (time.perf_counter_ns() - start) / 1e6
                python_ms.append(elapsed)
                cpp_ms.append(result.timing.total_ms)
                overhead_ms.append(elapsed - result.timing.total_ms)

    n = len(overhead_ms)
    print(f"dataset: {dataset} ({pipeline.frame_count} frames x {args.passes} passes = {n} calls)")
    print(f"{'':22}{'median':>10}{'mean':>10}{'p95':>10}{'max':>10}")
    for name, v in (("python call (ms)", python_ms), ("C++ call (ms)", cpp_ms), ("overhead (ms)", overhead_ms)):
        s = sorted(v)
        print(f"{name:22}{statistics.median(v):10.4f}{statistics.fmean(v):10.4f}{s[int(0.95 * (n - 1))]:10.4f}"
              f"{s[-1]:10.4f}")
    # A busy machine preempts some calls between C++'s timer and Python's, which inflates the mean;
    # the same frame tracked in every pass does the same work, so its smallest overhead over the passes
    # is the binding's cost without that noise.
    frames = pipeline.frame_count
    per_frame_min = [min(overhead_ms[p * frames + i] for p in range(args.passes)) for i in range(frames)]
    print(f"calls with overhead > 1 ms: {sum(o > 1.0 for o in overhead_ms)} of {n}")
    print(f"per frame, smallest overhead over the {args.passes} passes: mean {statistics.fmean(per_frame_min):.4f} ms, "
          f"max {max(per_frame_min):.4f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
