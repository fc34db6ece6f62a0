#!/usr/bin/env python3
"""Complete one LiDAR scan into a dense depth map and show it beside the camera image.

    PYTHONPATH=build/release/python python3 examples/python/complete_scan.py [dataset] [--frame 0]
        [--camera 0] [--method dilation|ipbasic] [--kernel diamond|rectangle|cross] [--size 5] [--out depth.png]

The scan is projected into the camera (z-buffered), then completed by RGB-L's inverse dilation with the
chosen kernel or by IP-Basic; numpy arrays in and out. Without a dataset a synthetic street is rendered.
Needs matplotlib.
"""

import argparse
import sys
import tempfile

import matplotlib
import numpy as np

import rgbl


def main() -> int:
    parser = argparse.ArgumentParser(description="Complete a scan and show the depth map beside the image.")
    parser.add_argument("dataset", nargs="?")
    parser.add_argument("--frame", type=int, default=0)
    parser.add_argument("--camera", type=int, default=0)
    parser.add_argument("--method", choices=["dilation", "ipbasic"], default="dilation")
    parser.add_argument("--kernel", default="diamond")
    parser.add_argument("--size", type=int, default=5)
    parser.add_argument("--out", help="write the figure to this file instead of showing it")
    args = parser.parse_args()
    if args.out:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with tempfile.TemporaryDirectory() as tmp:
        dataset = args.dataset or rgbl.write_synthetic_kitti(tmp, frames=args.frame + 1).sequence_dir
        sequence = rgbl.open_sequence(dataset)
        frame = sequence.load(args.frame)
    calibration = sequence.calibration.camera(args.camera)
    image = frame.images[args.camera]

    sparse = rgbl.project_to_depth(frame.scan, calibration)
    if args.method == "dilation":
        dense = rgbl.dilate_depth(sparse, kernel=args.kernel, size=args.size)
        method = f"inverse dilation, {args.kernel} {args.size}x{args.size}"
    else:
        dense = rgbl.ip_basic(sparse, mode="fast")
        method = "IP-Basic (fast)"
    print(f"{len(frame.scan)} points -> {np.count_nonzero(sparse)} pixels "
          f"({100 * rgbl.depth_density(sparse):.1f} %) -> {100 * rgbl.depth_density(dense):.1f} % after {method}")

    fig, axes = plt.subplots(2, 1, figsize=(12, 7))
    axes[0].imshow(image if image.ndim == 2 else image[:, :, ::-1], cmap="gray")  # BGR -> RGB
    axes[0].set_title(f"{sequence.name}, frame {frame.index}, camera {args.camera}")
    shown = np.where(dense > 0, dense, np.nan)
    im = axes[1].imshow(shown, cmap="turbo_r", vmin=0, vmax=np.nanpercentile(shown, 98))
    axes[1].set_title(f"depth: {method}")
    fig.colorbar(im, ax=axes[1], label="m", fraction=0.03)
    for ax in axes:
        ax.axis("off")
    if args.out:
        fig.savefig(args.out, dpi=100, bbox_inches="tight")
        print(f"wrote {args.out}")
    else:
        plt.show()
    return 0


if __name__ == "__main__":
    sys.exit(main())
