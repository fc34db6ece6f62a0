#!/usr/bin/env python3
"""Track a sequence with rgbl and plot the trajectory against the ground truth (top view).

    PYTHONPATH=build/release/python python3 examples/python/track_sequence.py [dataset] [--depth lidar]
                                                                            [--out trajectory.png]

dataset: a KITTI odometry sequences/NN, KITTI raw drive or TUM folder; without one a synthetic street with
exact ground truth is rendered into a temporary folder. Needs matplotlib (python3-matplotlib).
"""

import argparse
import sys
import tempfile

import matplotlib

import rgbl


def main() -> int:
    parser = argparse.ArgumentParser(description="Track a sequence and plot it against the ground truth.")
    parser.add_argument("dataset", nargs="?")
    parser.add_argument("--depth", default="lidar", help=f"depth source: {rgbl.depth_source_usage()}")
    parser.add_argument("--frames", type=int, default=0, help="0 = all")
    parser.add_argument("--out", help="write the plot to this file instead of showing it")
    args = parser.parse_args()
    if args.out:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with tempfile.TemporaryDirectory() as tmp:
        dataset = args.dataset or rgbl.write_synthetic_kitti(tmp, frames=80, path="curve").sequence_dir
        pipeline = rgbl.Pipeline(dataset, depth=args.depth, frames=args.frames)

        def progress(record: rgbl.FrameRecord, done: int, total: int) -> None:
            print(f"\rframe {done}/{total}: {record.result.state.name:<6} {record.result.timing.total_ms:6.1f} ms",
                  end="", file=sys.stderr)

        result = pipeline.run(progress)
        print(file=sys.stderr)

    poses = result.trajectory.poses  # N x 4 x 4, T_world_cam0 in the ground truth's world
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.plot(poses[:, 0, 3], poses[:, 2, 3], label=f"rgbl ({result.depth})")
    if len(result.ground_truth):
        truth = result.ground_truth
        ax.plot(truth[:, 0, 3], truth[:, 2, 3], "k--", label="ground truth")
    title = f"{result.sequence_name}: {len(poses)} frames, {result.count(rgbl.TrackState.Ok)} ok"
    if result.metrics:
        e = result.metrics.evaluation
        title += f"\nATE {e.ate.translation.rmse:.3f} m, drift {e.drift.percent:.2f} %"
        print(f"ATE {e.ate.translation.rmse:.3f} m, drift {e.drift.percent:.2f} % over {e.path_length:.0f} m")
    ax.set_title(title)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend()
    if args.out:
        fig.savefig(args.out, dpi=120, bbox_inches="tight")
        print(f"wrote {args.out}")
    else:
        plt.show()
    return 0


if __name__ == "__main__":
    sys.exit(main())
