#!/usr/bin/env python3
"""The keyframes' LiDAR pairs against the ground truth: how far each registered step is off.

    build/release/bin/rgbl -v run DRIVE --out RUN > LOG 2>&1
    scripts/lidar_pairs.py LOG RUN [--worst N]

LOG holds local mapping's debug line per keyframe pair ("LiDAR pair kept (...)" or "not kept: REASON"),
with the two frames and the registered motion T_cam_previous; RUN is the run's folder
(ground_truth_kitti.txt, trajectory_kitti.txt). For the kept pairs and for each reason a pair was not
kept, prints how far the registered step is off the truth's (translation, median and largest; rotation
per camera axis, RMS: pitch about x, yaw about y, roll about z) and, for comparison, how far the
written trajectory's step between the same frames is off. Then the N pairs furthest off (default 5) with
their probe loss. Needs the Python module (PYTHONPATH=build/release/python), python3-numpy and
python3-scipy.
"""
import argparse
import re

import numpy as np
import rgbl
from scipy.spatial.transform import Rotation

LINE = re.compile(r'LiDAR pair (kept|not kept: [a-z ]+) \(.*?probe loss (\S+?)[,;].*?frames (\d+) -> (\d+), '
                  r'T_cam_previous t (\S+) (\S+) (\S+) rad (\S+) (\S+) ([-0-9.e]+)\)')


def error(truth_b_a, measured_b_a):
    """Translation (m) and rotation vector (deg, camera axes) of inv(truth) * measured."""
    d = np.linalg.inv(truth_b_a) @ measured_b_a
    return d[:3, 3], np.degrees(Rotation.from_matrix(d[:3, :3]).as_rotvec())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('log')
    parser.add_argument('run')
    parser.add_argument('--worst', type=int, default=5)
    args = parser.parse_args()
    truth = rgbl.read_kitti_trajectory(f'{args.run}/ground_truth_kitti.txt')
    written = rgbl.read_kitti_trajectory(f'{args.run}/trajectory_kitti.txt')
    pairs = []
    with open(args.log, encoding='utf-8', errors='replace') as log:
        for line in log:
            m = LINE.search(line)
            if not m:
                continue
            kind, loss = m.group(1), float(m.group(2))
            a, b = int(m.group(3)), int(m.group(4))
            v = np.array([float(x) for x in m.groups()[4:]])
            measured = np.eye(4)
            measured[:3, :3] = Rotation.from_rotvec(v[3:]).as_matrix()
            measured[:3, 3] = v[:3]
            if max(a, b) >= len(truth):
                continue
            truth_b_a = np.linalg.inv(truth[b]) @ truth[a]
            t, r = error(truth_b_a, measured)
            tw, _ = error(truth_b_a, np.linalg.inv(written[b]) @ written[a])
            pairs.append({'kind': kind, 'loss': loss, 'a': a, 'b': b, 't': t, 'r': r, 'tw': tw,
                          'step': np.linalg.norm(truth_b_a[:3, 3])})
    if not pairs:
        print('no LiDAR pair lines in the log (run with -v, LiDAR depth, LocalMapping.LidarPairSigma > 0)')
        return
    print(f'{len(pairs)} pairs; errors against the truth (m, deg)')
    print('| pairs | n | registered: t median | t max | rot RMS pitch / yaw / roll | written trajectory: t median |')
    print('|---|---|---|---|---|---|')
    for kind in sorted({p['kind'] for p in pairs}):
        group = [p for p in pairs if p['kind'] == kind]
        t = np.array([np.linalg.norm(p['t']) for p in group])
        r = np.array([p['r'] for p in group])
        tw = np.array([np.linalg.norm(p['tw']) for p in group])
        rms = np.sqrt((r ** 2).mean(0))
        print(f'| {kind} | {len(group)} | {np.median(t):.4f} | {t.max():.4f} | '
              f'{rms[0]:.4f} / {rms[1]:.4f} / {rms[2]:.4f} | {np.median(tw):.4f} |')
    print(f'\nfurthest off (frames, kind, truth step m, registered off m, probe loss):')
    for p in sorted(pairs, key=lambda p: -np.linalg.norm(p['t']))[:args.worst]:
        print(f"  {p['a']:4d} -> {p['b']:4d}  {p['kind']:34s} {p['step']:.3f}  {np.linalg.norm(p['t']):.3f}  {p['loss']:.3f}")


if __name__ == '__main__':
    main()
