#!/usr/bin/env python3
"""Does a KITTI raw drive's OXTS ground truth agree with itself? (needs python3-numpy)

  scripts/oxts_consistency.py DRIVE_DIR      (the folder holding oxts/data/*.txt)

A car drives where it points (sideslip ~0 at town speed on a straight), so the direction of the
OXTS unit's own velocity (vn, ve) and of its GPS track should match its reported heading (yaw).
Prints the mean and largest offsets. rgbl's ground-truth poses take their positions from the GPS
track and their orientation from yaw: an offset here is an inconsistency of the truth itself.
"""
import glob
import sys

import numpy as np

d = np.array([np.loadtxt(f) for f in sorted(glob.glob(f"{sys.argv[1]}/oxts/data/*.txt"))])
lat, lon, yaw, vn, ve = d[:, 0], d[:, 1], d[:, 5], d[:, 6], d[:, 7]
earth = 6378137.0
x = np.radians(lon - lon[0]) * earth * np.cos(np.radians(lat[0]))
y = np.radians(lat - lat[0]) * earth
wrap = lambda a: (a + np.pi) % (2 * np.pi) - np.pi
velocity = np.degrees(wrap(np.arctan2(vn, ve) - yaw))
track = np.degrees(wrap(np.arctan2(np.diff(y), np.diff(x)) - 0.5 * (yaw[1:] + yaw[:-1])))
print(f"{len(d)} frames, heading change {np.degrees(wrap(yaw[-1] - yaw[0])):.2f} deg")
print(f"velocity direction - heading: mean {velocity.mean():+.2f} deg, max |.| {np.abs(velocity).max():.2f} deg")
print(f"GPS track direction - heading: mean {track.mean():+.2f} deg, max |.| {np.abs(track).max():.2f} deg")
