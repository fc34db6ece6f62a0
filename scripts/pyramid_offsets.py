#!/usr/bin/env python3
"""Where a pyramid level's FAST corners land at level 0, under two mappings (docs/features.md).

Builds rgbl's pyramid (each level cv::resize'd from the previous one, INTER_LINEAR, sizes rounded from
W / 1.2^l), detects FAST corners on every level, maps them to level 0 with `x * 1.2^l` (ORB-SLAM's and
rgbl's) and with the pixel-centre mapping `(x + 0.5) * W0 / Wl - 0.5` (what cv::resize does), and prints
the mean offset to the nearest level-0 corner. Needs python3-opencv and python3-numpy.

    scripts/pyramid_offsets.py ../shared/data/kitti/odometry/sequences/04/image_0/000000.png
"""
import sys

import cv2
import numpy as np


def corners(image, detector):
    return np.array([k.pt for k in detector.detect(image)], dtype=np.float64).reshape(-1, 2)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    image = cv2.imread(sys.argv[1], cv2.IMREAD_GRAYSCALE)
    if image is None:
        sys.exit(f"error: cannot read {sys.argv[1]} as an image")
    height, width = image.shape
    fast = cv2.FastFeatureDetector_create(20, True)
    level0 = corners(image, fast)
    level = image
    print("level  mapping  matched  mean offset x  mean offset y  (px at level 0, nearest level-0 corner minus mapped)")
    for l in range(1, 8):
        scale = 1.2 ** l
        level = cv2.resize(level, (round(width / scale), round(height / scale)), interpolation=cv2.INTER_LINEAR)
        found = corners(level, fast)
        if len(found) == 0:
            continue
        mapped = {
            "scale": found * scale,
            "centre": np.stack([(found[:, 0] + 0.5) * width / level.shape[1] - 0.5,
                                (found[:, 1] + 0.5) * height / level.shape[0] - 0.5], axis=1),
        }
        for name, points in mapped.items():
            offsets = []
            for p in points:
                d = level0 - p
                i = int(np.argmin((d * d).sum(axis=1)))
                if np.hypot(*d[i]) <= 0.75 * scale:
                    offsets.append(d[i])
            o = np.array(offsets).reshape(-1, 2)
            print(f"{l:5d}  {name:7s}  {len(o):7d}  {o[:, 0].mean():13.3f}  {o[:, 1].mean():13.3f}")


if __name__ == "__main__":
    main()
