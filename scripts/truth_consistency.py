#!/usr/bin/env python3
"""How close can any tracker get to this ground truth? Its own consistency, and the LiDAR's path.

  PYTHONPATH=build/release/python scripts/truth_consistency.py DRIVE RUN [--no-lidar]

DRIVE is anything `rgbl run` reads with a LiDAR and ground truth; RUN an `rgbl run --out` folder of it
(trajectory_kitti.txt, ground_truth_kitti.txt). Needs the Python module, python3-numpy and -scipy.

Two references besides the truth's positions:
- the dead-reckoned truth: the truth's own orientations, its own step lengths, each step along one
  fixed direction of the body (the mean of its steps' directions in the camera frame). A car drives
  where it points, so a consistent truth lies on it (sequence 04: 0.014 m). Its ATE against the
  truth's positions is the floor for any tracker whose camera moves along a fixed direction of itself.
- the LiDAR's path: consecutive scans registered point to plane (scripts/scan_icp_scale.py's
  registration; each started from the previous result, the first from the truth's step length
  straight ahead), chained and moved into the camera frame by the calibration: a second sensor
  that shares neither the camera, nor the tracker, nor the OXTS unit.
Prints ATE (rigid alignment) against both references, the end-point drift (first poses aligned, as
`rgbl run` does) and the path length over the truth's, for the run and the LiDAR's path.
"""
import os
import sys

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from scan_icp_scale import register, thin  # noqa: E402


def homogeneous(pose34):
    T = np.eye(4)
    T[:3] = pose34
    return T


def rigid_ate(p, q):
    """RMSE of p (N x 3) against q after the rigid motion that fits p onto q best (Umeyama, no scale)."""
    mp, mq = p.mean(0), q.mean(0)
    U, _, Vt = np.linalg.svd((q - mq).T @ (p - mp))
    D = np.eye(3)
    if np.linalg.det(U @ Vt) < 0:
        D[2, 2] = -1
    R = U @ D @ Vt
    e = (R @ (p - mp).T).T + mq - q
    return float(np.sqrt((e ** 2).sum(1).mean()))


def drift_percent(est, gt):
    """End-point error with the first poses aligned, in % of the truth's path."""
    T = homogeneous(gt[0]) @ np.linalg.inv(homogeneous(est[0])) @ homogeneous(est[-1])
    path = np.linalg.norm(np.diff(gt[:, :, 3], axis=0), axis=1).sum()
    return 100.0 * np.linalg.norm(T[:3, 3] - gt[-1, :, 3]) / path


def path_ratio(est, gt):
    length = lambda p: np.linalg.norm(np.diff(p[:, :, 3], axis=0), axis=1).sum()
    return length(est) / length(gt)


def dead_reckoned(gt):
    """The truth's orientations and step lengths, every step along the body's mean step direction."""
    n = len(gt)
    steps = np.diff(gt[:, :, 3], axis=0)
    lengths = np.linalg.norm(steps, axis=1)
    middle = Slerp(np.arange(n), Rotation.from_matrix(gt[:, :, :3]))(np.arange(n - 1) + 0.5).as_matrix()
    moving = lengths > 0.05  # a car standing still has no direction of travel
    body = np.einsum('nji,nj->ni', middle[moving], steps[moving] / lengths[moving, None])
    mean = body.mean(0)
    mean /= np.linalg.norm(mean)
    spread = np.degrees(np.arccos(np.clip(body @ mean, -1.0, 1.0)))
    p = np.vstack([gt[0, :, 3], gt[0, :, 3] + np.cumsum(lengths[:, None] * (middle @ mean), axis=0)])
    return p, spread


def lidar_path(drive, gt):
    import rgbl
    sequence = rgbl.open_sequence(drive, cameras=[False] * 4, depth=False)
    T_cam_lidar = np.asarray(sequence.calibration.T_cam0_lidar)
    scan = lambda k: thin(sequence.load(k, cameras=[False] * 4, depth=False).scan)
    first = np.linalg.inv(homogeneous(gt[0])) @ homogeneous(gt[1])
    guess = np.eye(4)
    guess[0, 3] = np.linalg.norm(first[:3, 3])  # the Velodyne's x points ahead
    T_first_lidar = [np.eye(4)]
    previous = scan(0)
    for k in range(1, len(gt)):
        current = scan(k)
        step = register(current, previous, guess)  # current scan -> previous scan's frame
        T_first_lidar.append(T_first_lidar[-1] @ step)
        guess, previous = step, current
    T_lidar_cam = np.linalg.inv(T_cam_lidar)
    poses = [homogeneous(gt[0]) @ T_cam_lidar @ T @ T_lidar_cam for T in T_first_lidar]
    return np.array([T[:3] for T in poses])


def main(argv):
    args = [a for a in argv[1:] if not a.startswith('--')]
    if len(args) != 2:
        sys.exit(__doc__)
    drive, run = args
    gt = np.loadtxt(os.path.join(run, 'ground_truth_kitti.txt')).reshape(-1, 3, 4)
    est = np.loadtxt(os.path.join(run, 'trajectory_kitti.txt')).reshape(-1, 3, 4)
    n = min(len(gt), len(est))
    gt, est = gt[:n], est[:n]
    reckoned, spread = dead_reckoned(gt)
    print(f'{n} frames. The truth\'s steps against its own orientation: {spread.mean():.2f} deg from their mean '
          f'direction in the body (largest {spread.max():.2f} deg)')
    print(f'floor: the dead-reckoned truth against the truth\'s positions: ATE {rigid_ate(reckoned, gt[:, :, 3]):.3f} m')
    rows = [('run', est)]
    if '--no-lidar' not in argv:
        rows.append(('LiDAR registration', lidar_path(drive, gt)))
    print(f'{"":20s} {"ATE m":>7s} {"ATE m vs dead-reckoned":>23s} {"drift %":>8s} {"path / truth":>13s}')
    for name, poses in rows:
        print(f'{name:20s} {rigid_ate(poses[:, :, 3], gt[:, :, 3]):7.3f} {rigid_ate(poses[:, :, 3], reckoned):23.3f} '
              f'{drift_percent(poses, gt):8.2f} {path_ratio(poses, gt):13.4f}')


if __name__ == '__main__':
    main(sys.argv)
