"""The hand's path from joint codes: forward kinematics of a published chain, and a reading that does
not depend on which of the redundant arm's joint configurations reached the hand."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from data.nao import JOINT_LIMITS, NAO_ARM, forward_kinematics, inverse_kinematics
from model.encoding.kinematics import HAND_PATH_COLUMNS, STEP_GAIN, ArmChain, hand_positions, read_hand_path
from model.encoding.proprioception import encode_joints


def test_forward_kinematics_agrees_with_the_nao_chain_of_data() -> None:
    q = np.random.default_rng(0).uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], (40, 5))
    ours = hand_positions(torch.tensor(q, dtype=torch.float64).float(), NAO_ARM).numpy()
    reference = np.stack([forward_kinematics(x)["hand"] for x in q])
    np.testing.assert_allclose(ours, reference, atol=1e-6)


def test_the_reading_keeps_the_codes_and_adds_relative_position_and_displacement() -> None:
    lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    q = np.linspace(lo + 0.3 * (hi - lo), lo + 0.7 * (hi - lo), 7)  # within the limits: codes in (0, 1)
    codes = torch.from_numpy(encode_joints(q, JOINT_LIMITS))[None]
    read = read_hand_path(codes, NAO_ARM)
    assert read.shape == (1, 7, 5 + HAND_PATH_COLUMNS)
    torch.testing.assert_close(read[..., :5], codes)
    hand = np.stack([forward_kinematics(x)["hand"] for x in q])
    np.testing.assert_allclose(read[0, :, 5:8].numpy(), (hand - hand[0]) / NAO_ARM.reach, atol=1e-5)
    step = np.vstack([np.zeros(3), np.diff(hand, axis=0)]) * STEP_GAIN / NAO_ARM.reach
    np.testing.assert_allclose(read[0, :, 8:].numpy(), step, atol=1e-4)


def test_two_joint_configurations_on_one_hand_path_read_the_same() -> None:
    """The arm is redundant: elbow high and elbow low reach the same points with other angles."""
    path = [np.array([0.15, -0.12, 0.02]) + np.array([0.0, 0.01, -0.005]) * t for t in range(6)]
    high, low = [], []
    q_high, q_low = np.array([0.3, -0.3, -1.2, 0.8, 0.0]), np.array([0.3, -0.3, 1.2, 0.8, 0.0])
    for target in path:
        q_high = inverse_kinematics(
            target, q_high, preference=np.array([0.3, -0.3, -1.2, 0.8, 0.0]), min_iterations=20
        )
        q_low = inverse_kinematics(
            target, q_low, preference=np.array([0.3, -0.3, 1.2, 0.8, 0.0]), min_iterations=20
        )
        high.append(q_high)
        low.append(q_low)
    high, low = np.array(high), np.array(low)
    assert np.abs(high - low).max() > 0.5  # other joint angles ...
    read = [
        read_hand_path(torch.from_numpy(encode_joints(q, JOINT_LIMITS))[None], NAO_ARM) for q in (high, low)
    ]
    assert (read[0][..., :5] - read[1][..., :5]).abs().max() > 0.1
    # ... one hand path, to IK's tolerance (0.1 mm: 5e-4 of the reach, x STEP_GAIN per step)
    torch.testing.assert_close(read[0][..., 5:8], read[1][..., 5:8], atol=1e-3, rtol=0)
    torch.testing.assert_close(read[0][..., 8:], read[1][..., 8:], atol=1e-2, rtol=0)


def test_a_chain_checks_itself_and_round_trips_through_a_dict() -> None:
    assert ArmChain.from_dict(NAO_ARM.to_dict()) == NAO_ARM
    assert NAO_ARM.joints == 5 and 0.2 < NAO_ARM.reach < 0.25  # the NAO's arm is about 22 cm long
    with pytest.raises(ValueError, match="one origin"):
        ArmChain(NAO_ARM.origins[:4], NAO_ARM.axes, NAO_ARM.hand_offset, NAO_ARM.limits)
    with pytest.raises(ValueError, match="min < max"):
        ArmChain(NAO_ARM.origins, NAO_ARM.axes, NAO_ARM.hand_offset, ((1.0, 0.0),) * 5)
