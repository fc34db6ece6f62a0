#!/usr/bin/env python3
"""A copy of a KITTI drive whose scans are moved to the images' time, outside rgbl (docs/accuracy.md,
"The LiDAR's sweep"): each return measured DELTA seconds before its image (plus, with SPIN, the sweep:
SPIN * azimuth / 2 pi * 0.1 s; +1 = clockwise from above, -1 = the other way) is moved by the camera's
motion over that time, from the ground truth's steps (first order). Calibration, timestamps, ground
truth and scans come from rgbl's loader; the images and the other files are linked, not copied. Used to
check what rgbl's LiDAR.TimeOffset does, and to try the sweep.

  export PYTHONPATH=build/release/python
  scripts/scan_time_shift.py $RX 0.0169 /tmp/rx-shift 1
  rgbl -q run /tmp/rx-shift/2011_09_26/2011_09_26_drive_0009_sync --config t0.yaml   # LiDAR.TimeOffset: 0

DRIVE: a KITTI raw <date>/<drive>_sync folder or an odometry sequences/NN folder (poses/ is linked
beside the copy). Needs python3-numpy and python3-opencv.
"""
import os
import sys

import cv2
import numpy as np

import rgbl


def link_all_but(src, dst, skip):
    os.makedirs(dst, exist_ok=True)
    for name in os.listdir(src):
        if name != skip and not os.path.exists(os.path.join(dst, name)):
            os.symlink(os.path.join(src, name), os.path.join(dst, name))


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit(__doc__)
    src, delta, out = os.path.abspath(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
    spin = float(sys.argv[4]) if len(sys.argv) == 5 else 0.0
    seq = rgbl.open_sequence(src)
    if seq.ground_truth is None:
        sys.exit(f"{src}: no ground truth, which gives the motion")
    poses = seq.ground_truth.poses
    T_cam_lidar = seq.calibration.T_cam0_lidar
    T_lidar_cam = np.linalg.inv(T_cam_lidar)

    if seq.format == rgbl.DatasetFormat.kitti_raw:  # <date>/<drive>: calibration one level up
        day = os.path.dirname(src)
        drive = os.path.join(out, os.path.basename(day), os.path.basename(src))
        link_all_but(day, os.path.dirname(drive), os.path.basename(src))
        link_all_but(src, drive, "velodyne_points")
        link_all_but(os.path.join(src, "velodyne_points"), os.path.join(drive, "velodyne_points"), "data")
        scan_dir, name = os.path.join(drive, "velodyne_points", "data"), "{:010}.bin"
    else:  # sequences/NN, with poses/ two levels up
        drive = os.path.join(out, "sequences", os.path.basename(src))
        link_all_but(src, drive, "velodyne")
        poses_dir = os.path.join(os.path.dirname(os.path.dirname(src)), "poses")
        if not os.path.exists(os.path.join(out, "poses")):
            os.symlink(poses_dir, os.path.join(out, "poses"))
        scan_dir, name = os.path.join(drive, "velodyne"), "{:06}.bin"
    os.makedirs(scan_dir, exist_ok=True)

    for i in range(len(seq)):
        a, b = (i - 1, i) if i > 0 else (0, 1)
        step = np.linalg.inv(poses[a]) @ poses[b]  # camera a -> b, in a's frame
        rotation, _ = cv2.Rodrigues(step[:3, :3])
        rotation, translation = rotation.ravel(), step[:3, 3]
        points = np.array(seq.load(i, cameras=[False] * 4, depth=False).scan, dtype=np.float32)
        azimuth = np.arctan2(points[:, 1], points[:, 0]).astype(np.float64)
        # frames of motion between each return and the image
        f = (delta + spin * azimuth / (2 * np.pi) * 0.1) / (seq.timestamp(b) - seq.timestamp(a))
        p = points[:, :3].astype(np.float64) @ T_cam_lidar[:3, :3].T + T_cam_lidar[:3, 3]
        # where the point is seen from at the image's time: undo f of the step (first order in the rotation)
        p = p - f[:, None] * translation[None, :]
        p = p - np.cross(f[:, None] * rotation[None, :], p)
        points[:, :3] = (p @ T_lidar_cam[:3, :3].T + T_lidar_cam[:3, 3]).astype(np.float32)
        points.tofile(os.path.join(scan_dir, name.format(i)))


if __name__ == "__main__":
    main()
