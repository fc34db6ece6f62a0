#!/usr/bin/python3
"""Real KITTI drives made harder the way cameras fail on the road, for the accuracy suite.

    scripts/degrade.py SOURCE DEST [--blur K] [--gain G] [--seed S] [--rings N]

SOURCE is a KITTI odometry sequence folder (sequences/NN) or a KITTI raw drive folder
(<date>/<date>_drive_XXXX_sync). DEST receives the same layout: every grey image (image_0, image_1,
image_00/data, image_01/data) degraded, everything else (scans, calibration, timestamps, poses, OXTS)
linked, so rgbl reads DEST exactly as it reads SOURCE. The LiDAR (unless --rings) and the ground truth
stay real.

--blur K   motion blur of a forward-driving camera: each pixel is averaged along the ray from the
           principal point over K per mille of its distance to it, centred on the pixel (K = 25: 15 px
           at the image's side edges, 0 straight ahead), as a longer exposure at speed smears what
           passes close by. Centred, as an exposure centred on the frame's time (the simulator's):
           averaged only inwards, the image would also be magnified by K/2 per mille, a focal-length
           error that is not blur.
--gain G   exposure jumps: each frame's intensity scaled by a factor drawn uniformly from [1-G, 1+G]
           (seeded), with a gamma drawn from [1-G/2, 1+G/2]: auto-exposure hunting under trees.
--rings N  a sparser LiDAR: every scan keeps every Nth of its rings (2: a 32-ring sensor from KITTI's
           HDL-64, 4: 16 rings), the images untouched. KITTI's scans (and the simulator's) hold their
           returns ring by ring, each one sweep of the azimuth, so a ring starts where the azimuth
           goes back; a scan that does not come out at 61-71 rings is refused.

Needs Debian's python3-opencv and python3-numpy (run with /usr/bin/python3).
"""
import argparse
import os
import random
import sys

import cv2
import numpy as np

GREY_FOLDERS = ("image_0", "image_1", os.path.join("image_00", "data"), os.path.join("image_01", "data"))
SCAN_FOLDERS = ("velodyne", os.path.join("velodyne_points", "data"))


def keep_rings(points, every, path):
    """The returns of every `every`-th ring of a scan stored ring by ring (N x 4 float32)."""
    # within a ring the azimuth only moves on (gaps where the beam saw sky skip ahead); back by more
    # than 90 deg is the next ring's start (a whole turn on KITTI 04, half of one on its raw drives,
    # whose scans were cropped ahead)
    ends = np.diff(np.arctan2(points[:, 1], points[:, 0])) < -np.pi / 2
    ring = np.concatenate([[0], np.cumsum(ends)])
    if len(points) > 1000 and not 60 <= ring[-1] <= 70:
        sys.exit(f"degrade.py: {path}: {ring[-1]} ring starts, not a 64-ring scan stored ring by ring")
    return points[ring % every == 0]


def radial_blur(image, principal, strength, samples=16):
    h, w = image.shape
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    dx, dy = xs - principal[0], ys - principal[1]
    acc = np.zeros((h, w), np.float32)
    for i in range(samples):
        s = 1.0 + strength * (0.5 - i / (samples - 1))  # 1 + K/2 .. 1 - K/2: no magnification
        acc += cv2.remap(image, principal[0] + dx * s, principal[1] + dy * s, cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REFLECT)
    return acc / samples


def principal_point(source):
    calib = os.path.join(source, "calib.txt")
    if os.path.isfile(calib):
        with open(calib) as f:
            p0 = [float(v) for v in f.readline().split()[1:]]
        return p0[2], p0[6]
    cam_to_cam = os.path.join(os.path.dirname(os.path.abspath(source)), "calib_cam_to_cam.txt")
    with open(cam_to_cam) as f:
        for line in f:
            if line.startswith("P_rect_00:"):
                p = [float(v) for v in line.split()[1:]]
                return p[2], p[6]
    sys.exit(f"degrade.py: no calib.txt in {source} and no P_rect_00 in {cam_to_cam}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("source")
    parser.add_argument("dest")
    parser.add_argument("--blur", type=float, default=0.0)
    parser.add_argument("--gain", type=float, default=0.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--rings", type=int, default=1)
    args = parser.parse_args()
    if args.rings < 1:
        sys.exit("degrade.py: --rings takes a whole number >= 1")
    source = os.path.abspath(args.source.rstrip("/"))
    dest = os.path.abspath(args.dest.rstrip("/"))
    principal = principal_point(source)
    rng = random.Random(args.seed)
    os.makedirs(dest, exist_ok=True)

    # a raw drive's calibration lives one level up: link it next to DEST
    for name in ("calib_cam_to_cam.txt", "calib_velo_to_cam.txt", "calib_imu_to_velo.txt"):
        path = os.path.join(os.path.dirname(source), name)
        target = os.path.join(os.path.dirname(dest), name)
        if os.path.isfile(path) and not os.path.exists(target):
            os.symlink(path, target)
    # an odometry sequence's poses live two levels up (poses/NN.txt)
    poses = os.path.join(os.path.dirname(os.path.dirname(source)), "poses", os.path.basename(source) + ".txt")
    if os.path.isfile(poses):
        os.makedirs(os.path.join(os.path.dirname(os.path.dirname(dest)), "poses"), exist_ok=True)
        target = os.path.join(os.path.dirname(os.path.dirname(dest)), "poses", os.path.basename(dest) + ".txt")
        if not os.path.exists(target):
            os.symlink(poses, target)

    grey = [os.path.join(source, g) for g in GREY_FOLDERS if os.path.isdir(os.path.join(source, g))]
    if args.blur <= 0 and args.gain <= 0:
        grey = []  # the images as they are, linked
    scans = [os.path.join(source, g) for g in SCAN_FOLDERS if os.path.isdir(os.path.join(source, g))]
    if args.rings == 1:
        scans = []
    rewritten = grey + scans
    for entry in sorted(os.listdir(source)):
        path = os.path.join(source, entry)
        target = os.path.join(dest, entry)
        if os.path.exists(target):
            continue
        if path in rewritten:
            os.makedirs(target)
        elif any(g.startswith(path + os.sep) for g in rewritten):
            os.makedirs(target)  # image_00: its data/ is degraded, timestamps.txt linked
            for inner in os.listdir(path):
                if os.path.join(path, inner) not in rewritten:
                    os.symlink(os.path.join(path, inner), os.path.join(target, inner))
                else:
                    os.makedirs(os.path.join(target, inner))
        else:
            os.symlink(path, target)

    for folder in scans:
        out = os.path.join(dest, os.path.relpath(folder, source))
        kept = []
        for name in sorted(os.listdir(folder)):
            points = np.fromfile(os.path.join(folder, name), np.float32).reshape(-1, 4)
            sparse = keep_rings(points, args.rings, os.path.join(folder, name))
            kept.append(len(sparse) / max(1, len(points)))
            sparse.tofile(os.path.join(out, name))
        print(f"degrade.py: {len(kept)} scans, 1 ring in {args.rings} kept ({100 * np.mean(kept):.0f} % of the returns)"
              f" -> {dest}")
    if not grey:
        return
    frames = sorted(os.listdir(grey[0]))
    factors = [(rng.uniform(1 - args.gain, 1 + args.gain), rng.uniform(1 - args.gain / 2, 1 + args.gain / 2))
               for _ in frames]
    for folder in grey:
        out = os.path.join(dest, os.path.relpath(folder, source))
        for name, (gain, gamma) in zip(sorted(os.listdir(folder)), factors):
            image = cv2.imread(os.path.join(folder, name), cv2.IMREAD_GRAYSCALE).astype(np.float32)
            if args.blur > 0:
                image = radial_blur(image, principal, args.blur / 1000.0)
            if args.gain > 0:
                image = 255.0 * np.power(np.clip(image * gain / 255.0, 0, 1), gamma)
            cv2.imwrite(os.path.join(out, name), np.clip(image + 0.5, 0, 255).astype(np.uint8))
    print(f"degrade.py: {len(frames)} frames x {len(grey)} cameras -> {dest}")


if __name__ == "__main__":
    main()
