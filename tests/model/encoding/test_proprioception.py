"""Proprioception encoding: joint angles scaled to [0, 1] by the joint limits (paper 4.1.1)."""

from __future__ import annotations

import numpy as np
import pytest

from model.encoding.proprioception import decode_joints, encode_joints

# The published NAO right-arm limits (radians), written out so the test does not import data/.
LIMITS = np.array(
    [
        [-2.0857, 2.0857],  # RShoulderPitch
        [-1.3265, 0.3142],  # RShoulderRoll
        [-2.0857, 2.0857],  # RElbowYaw
        [0.0349, 1.5446],  # RElbowRoll
        [-1.8238, 1.8238],  # RWristYaw
    ]
)


def test_limits_map_to_zero_and_one_and_midpoint_to_half() -> None:
    joints = np.stack([LIMITS[:, 0], LIMITS[:, 1], LIMITS.mean(axis=1)])
    enc = encode_joints(joints, LIMITS)
    assert enc.dtype == np.float32 and enc.shape == (3, 5)
    np.testing.assert_allclose(enc[0], 0.0, atol=1e-7)
    np.testing.assert_allclose(enc[1], 1.0, atol=1e-7)
    np.testing.assert_allclose(enc[2], 0.5, atol=1e-6)


def test_decode_inverts_encode_within_limits() -> None:
    rng = np.random.default_rng(0)
    joints = rng.uniform(LIMITS[:, 0], LIMITS[:, 1], size=(50, 5))
    np.testing.assert_allclose(decode_joints(encode_joints(joints, LIMITS), LIMITS), joints, atol=1e-5)


def test_out_of_limit_angles_are_clipped_into_unit_interval() -> None:
    joints = np.stack([LIMITS[:, 0] - 0.5, LIMITS[:, 1] + 0.5])
    enc = encode_joints(joints, LIMITS)
    np.testing.assert_array_equal(enc, [[0.0] * 5, [1.0] * 5])


@pytest.mark.parametrize(
    ("joints", "message"),
    [
        (np.zeros((10, 4)), r"shape \(T, 5\)"),
        (np.zeros(5), r"shape \(T, 5\)"),
        (np.zeros((0, 5)), "empty"),
        (np.array([[0.0, 0.0, np.nan, 0.0, 0.0]]), "NaN"),
        (np.array([["a"] * 5]), "numeric"),
    ],
)
def test_bad_joint_arrays_raise_clear_value_error(joints: np.ndarray, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        encode_joints(joints, LIMITS)


@pytest.mark.parametrize(
    ("limits", "message"),
    [
        (LIMITS[:4], r"shape \(5, 2\)"),
        (LIMITS[:, ::-1], "min < max"),
        (np.where(np.eye(5, 2, dtype=bool), np.nan, LIMITS), "NaN"),
    ],
)
def test_bad_limits_raise_clear_value_error(limits: np.ndarray, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        encode_joints(np.zeros((3, 5)), limits)
