#!/usr/bin/env python3
"""How far rgbl's keypoints of each pyramid level sit from where the exact geometry puts them
(docs/features.md, "Keypoint coordinates across levels").

On a simulated sequence with exact depth images and poses, level-0 keypoints of frame i are lifted
with the depth image, moved by the true relative pose and projected into frames i+1..i+4; each lands
next to the keypoint it matches there (mutual best, Hamming <= 40). The mean offset per level of that
keypoint is printed for two maps from level to image pixels: `x * 1.2^l` (ORB-SLAM's) and
`(x + 0.5) * W0 / Wl - 0.5` (cv::resize's pixel-centre map at the levels' real size ratio). The level
pixel is recovered from the keypoint, whichever map the build uses. Needs the Python module
(build/release/python), python3-numpy and python3-opencv.

    build/release/bin/rgbl demo --path straight --frames 64 --depth precomputed --keep /tmp/street
    PYTHONPATH=build/release/python scripts/level_offsets.py /tmp/street
"""
import sys
from pathlib import Path

import cv2
import numpy as np
import rgbl


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    root = Path(sys.argv[1])
    seq = root / "sequences" / "00"
    if not (seq / "depth").is_dir():
        sys.exit(f"error: {seq}/depth missing: keep a dataset of `rgbl demo --depth precomputed`")
    poses = np.loadtxt(root / "poses" / "00.txt").reshape(-1, 3, 4)
    P = np.loadtxt(seq / "calib.txt", usecols=range(1, 13), max_rows=1).reshape(3, 4)
    fx, fy, cx, cy = P[0, 0], P[1, 1], P[0, 2], P[1, 2]
    options = rgbl.OrbOptions()
    extractor = rgbl.OrbExtractor(options)
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)

    def T_world_cam(i):
        T = np.eye(4)
        T[:3, :] = poses[i]
        return T

    def image(i):
        return cv2.imread(str(seq / "image_0" / f"{i:06d}.png"), cv2.IMREAD_GRAYSCALE)

    extracted = {}

    def extract(i):  # each frame is the target of up to four pairs
        if i not in extracted:
            extracted[i] = extractor.extract(image(i))
        return extracted[i]

    height, width = image(0).shape
    # the extractor's level sizes: float scales multiplied level by level, sizes rounded half away
    scales = [np.float32(1.0)]
    for _ in range(1, options.num_levels):
        scales.append(np.float32(scales[-1] * np.float32(options.scale_factor)))
    sizes = [(int(np.floor(np.float32(width) / s + np.float32(0.5))),
              int(np.floor(np.float32(height) / s + np.float32(0.5)))) for s in scales]

    def level_pixel(x, y, level):
        # whichever map made (x, y), the level pixel is whole under it
        s = scales[level]
        plain = np.array([x / s, y / s])
        w, h = sizes[level]
        centred = np.array([(x + 0.5) * w / width - 0.5, (y + 0.5) * h / height - 0.5])
        return plain if np.abs(plain - np.round(plain)).max() < 1e-3 else np.round(centred)

    offsets = {}  # level -> [(dx, dy) under x * scale, (dx, dy) pixel-centre]
    frames = len(poses)
    for i in range(0, frames - 4, 2):
        ka, da = extract(i)
        depth = cv2.imread(str(seq / "depth" / f"{i:06d}.png"), cv2.IMREAD_ANYDEPTH).astype(np.float64) / 256.0
        level0 = ka["level"] == 0
        ka, da = ka[level0], np.ascontiguousarray(da[level0])
        extracted.pop(i - 2, None)
        for k in range(1, 5):
            kb, db = extract(i + k)
            T_b_a = np.linalg.inv(T_world_cam(i + k)) @ T_world_cam(i)
            for m in matcher.match(da, np.ascontiguousarray(db)):
                if m.distance > 40:
                    continue
                u, v = float(ka["x"][m.queryIdx]), float(ka["y"][m.queryIdx])
                z = depth[int(round(v)), int(round(u))]
                if z <= 0:
                    continue
                q = T_b_a @ np.array([(u - cx) / fx * z, (v - cy) / fy * z, z, 1.0])
                projected = np.array([fx * q[0] / q[2] + cx, fy * q[1] / q[2] + cy])
                b = kb[m.trainIdx]
                level = int(b["level"])
                lx, ly = level_pixel(float(b["x"]), float(b["y"]), level)
                plain = np.array([lx, ly]) * scales[level]
                w, h = sizes[level]
                centred = np.array([(lx + 0.5) * width / w - 0.5, (ly + 0.5) * height / h - 0.5])
                if np.abs(centred - projected).max() > 4.0 * scales[level]:
                    continue  # a wrong match, not an offset
                offsets.setdefault(level, []).append(np.r_[plain - projected, centred - projected])
    print("| level | matches | x * 1.2^l: mean dx, dy (px) | pixel-centre: mean dx, dy (px) | standard error |")
    print("|---|---|---|---|---|")
    for level in sorted(offsets):
        o = np.array(offsets[level])
        mean = o.mean(axis=0)
        error = o[:, 2:].std(axis=0).max() / np.sqrt(len(o))
        print(f"| {level} | {len(o)} | {mean[0]:+.3f}, {mean[1]:+.3f} | {mean[2]:+.3f}, {mean[3]:+.3f} | {error:.3f} |")


if __name__ == "__main__":
    main()
