"""Trajectory metrics against values computed by hand, and poses shared without copies."""

import math

import numpy as np
import pytest

import rgbl


def straight(n=11, step=1.0):
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[:, 2, 3] = np.arange(n) * step  # driving along z
    return poses


def test_ate_of_a_shifted_trajectory():
    truth = straight()
    estimate = truth.copy()
    estimate[:, 0, 3] += 0.3
    assert rgbl.absolute_trajectory_error(estimate, truth).translation.rmse == pytest.approx(0, abs=1e-9)
    unaligned = rgbl.absolute_trajectory_error(estimate, truth, align=False)
    assert unaligned.translation.rmse == pytest.approx(0.3)
    assert unaligned.errors == pytest.approx([0.3] * 11)
    assert rgbl.absolute_trajectory_error(estimate, truth).T_gt_est[0, 3] == pytest.approx(-0.3)


def test_rpe_and_drift_of_a_scaled_trajectory():
    truth = straight()
    estimate = straight(step=1.1)  # 10 % too long
    rpe = rgbl.relative_pose_error(estimate, truth)
    assert rpe.translation.rmse == pytest.approx(0.1)
    assert rpe.rotation_deg.max == pytest.approx(0.0, abs=1e-9)
    assert len(rpe.translation_errors) == 10
    drift = rgbl.end_point_drift(estimate, truth)
    assert drift.path_length == pytest.approx(10.0)
    assert drift.end_error == pytest.approx(1.0)
    assert drift.percent == pytest.approx(10.0)
    assert rgbl.trajectory_distances(truth) == pytest.approx(np.arange(11.0))


def test_kitti_metric_of_a_scaled_trajectory():
    truth = straight(n=41)
    estimate = straight(n=41, step=1.05)
    metric = rgbl.kitti_metric(estimate, truth, lengths=[10.0, 20.0], step_size=1)
    # a segment ends at the first frame *beyond* L metres: 11 m for L = 10 (start frames 0..29), 21 m
    # for L = 20 (0..19); each is 5 % too long, over L: (30 x 11 / 10 + 20 x 21 / 20) x 5 % / 50
    assert metric.segments == 50
    assert metric.t_err_percent == pytest.approx((30 * 1.1 + 20 * 1.05) * 5.0 / 50)
    assert [p.t_err_percent for p in metric.per_length] == pytest.approx([5.5, 5.25])
    assert metric.r_err_deg_per_100m == pytest.approx(0.0, abs=1e-9)
    assert [p.length for p in metric.per_length] == [10.0, 20.0]
    no_segments = rgbl.kitti_metric(estimate, truth)  # 40 m: shorter than KITTI's 100 m
    assert no_segments.segments == 0 and math.isnan(no_segments.t_err_percent)
    everything = rgbl.evaluate_trajectory(estimate, truth)
    assert everything.poses == 41 and everything.drift.percent == pytest.approx(5.0)


def test_rotation_error_of_a_turning_estimate():
    truth = straight(n=3)
    estimate = truth.copy()
    c, s = math.cos(math.radians(2)), math.sin(math.radians(2))
    estimate[2, :3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    rpe = rgbl.relative_pose_error(estimate, truth)
    assert rpe.rotation_errors_deg == pytest.approx([0.0, 2.0], abs=1e-9)


def test_lengths_must_match():
    with pytest.raises(ValueError, match="equally many"):
        rgbl.absolute_trajectory_error(straight(5), straight(6))
    with pytest.raises(TypeError, match="4 x 4"):
        rgbl.absolute_trajectory_error(np.zeros((5, 3, 4)), np.zeros((5, 3, 4)))


def test_trajectory_files_round_trip_exactly(tmp_path):
    rng = np.random.default_rng(2)
    poses = straight(7)
    poses[:, :3, 3] += rng.normal(size=(7, 3)) / 3.0
    rgbl.write_kitti_trajectory(tmp_path / "t.txt", poses)
    back = rgbl.read_kitti_trajectory(tmp_path / "t.txt")
    assert back.shape == (7, 4, 4) and np.array_equal(back, poses)  # shortest round-trip numbers
    # returned poses are Eigen's column-major buffer seen through strides, not a copy
    assert back.strides == (128, 8, 32) and not back.flags.owndata and back.base is not None
    trajectory = rgbl.Trajectory(poses, timestamps=np.arange(7) * 0.1)
    rgbl.write_tum_trajectory(tmp_path / "t.tum", trajectory)
    tum = rgbl.read_tum_trajectory(tmp_path / "t.tum")
    assert np.allclose(tum.poses, poses, atol=1e-12) and np.array_equal(tum.timestamps, np.arange(7) * 0.1)
    assert np.shares_memory(tum.poses, tum.poses)  # two reads of one object: one buffer
