"""C++ exceptions arrive as Python exceptions with their message and details."""

import numpy as np
import pytest

import rgbl


def test_config_error_is_a_value_error_naming_the_key():
    with pytest.raises(ValueError) as info:
        rgbl.dilate_depth(np.zeros((8, 8), np.float32), kernel="hexagon")
    assert isinstance(info.value, rgbl.ConfigError)
    assert isinstance(info.value, rgbl.Error)
    assert info.value.key == "kernel"
    assert "diamond, rectangle, cross" in str(info.value)


def test_even_kernel_size_is_a_config_error():
    with pytest.raises(rgbl.ConfigError) as info:
        rgbl.dilate_depth(np.zeros((8, 8), np.float32), size=4)
    assert "size" in info.value.key


def test_parse_error_is_an_os_error_naming_the_file(tmp_path):
    bad = tmp_path / "trajectory.txt"
    bad.write_text("1 0 0 0\n0 1 0 0\n")
    with pytest.raises(OSError) as info:
        rgbl.read_kitti_trajectory(bad)
    assert isinstance(info.value, rgbl.ParseError)
    assert info.value.file == str(bad)
    assert info.value.line == 1
    assert str(bad) in str(info.value)


def test_opening_a_missing_dataset_names_it(tmp_path):
    with pytest.raises(rgbl.Error, match="nothing-here"):
        rgbl.open_sequence(tmp_path / "nothing-here")


def test_unknown_depth_source_lists_the_known_ones(camera):
    with pytest.raises(rgbl.ConfigError) as info:
        rgbl.make_depth_source("sonar", rgbl.CameraCalibration(camera))
    assert info.value.key == "--depth"
    for name in rgbl.depth_source_names():
        assert name in str(info.value)


def test_wrong_array_types_are_type_errors(camera):
    with pytest.raises(TypeError, match="scan"):
        rgbl.project_to_depth(np.zeros((5, 3), np.float32), rgbl.CameraCalibration(camera))
    with pytest.raises(TypeError, match="sparse"):
        rgbl.dilate_depth(np.zeros((4, 4, 2), np.float32))
