"""NAO right-arm kinematics: published limits, FK at known poses, URDF agreement, IK accuracy."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from data.nao import (
    JOINT_LIMITS,
    JOINT_NAMES,
    URDF_PATH,
    forward_kinematics,
    inverse_kinematics,
)

SHOULDER = np.array([0.0, -0.098, 0.100])


def test_joint_limits_are_the_published_nao_v5_ranges() -> None:
    assert JOINT_NAMES == ("RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll", "RWristYaw")
    expected = [[-2.0857, 2.0857], [-1.3265, 0.3142], [-2.0857, 2.0857], [0.0349, 1.5446], [-1.8238, 1.8238]]
    np.testing.assert_allclose(JOINT_LIMITS, expected)


def test_zero_pose_points_the_arm_straight_forward() -> None:
    p = forward_kinematics(np.zeros(5))
    np.testing.assert_allclose(p["shoulder"], SHOULDER)
    np.testing.assert_allclose(p["elbow"], SHOULDER + [0.105, -0.015, 0.0], atol=1e-12)
    np.testing.assert_allclose(p["wrist"], SHOULDER + [0.105 + 0.05595, -0.015, 0.0], atol=1e-12)
    # hand = shoulder + (UpperArm + LowerArm + HandOffsetX, -ElbowOffsetY, -HandOffsetZ)
    np.testing.assert_allclose(p["hand"], [0.2187, -0.113, 0.08769], atol=1e-12)


def test_shoulder_pitch_of_90_degrees_hangs_the_arm_down() -> None:
    p = forward_kinematics([np.pi / 2, 0, 0, 0, 0])
    np.testing.assert_allclose(p["wrist"], SHOULDER + [0.0, -0.015, -(0.105 + 0.05595)], atol=1e-12)
    # the hand offset rotates with the arm: HandOffsetZ now points backwards (-x)
    np.testing.assert_allclose(p["hand"], SHOULDER + [-0.01231, -0.015, -0.2187 + 0.0], atol=1e-12)


def test_shoulder_roll_outward_moves_the_right_arm_to_the_right() -> None:
    p = forward_kinematics([0, -np.pi / 2 + 0.3, 0, 0, 0])
    assert p["hand"][1] < SHOULDER[1] - 0.15


def test_elbow_roll_at_its_limit_folds_the_forearm_towards_the_body() -> None:
    p = forward_kinematics([0, 0, 0, 1.5446, 0])
    forearm = p["wrist"] - p["elbow"]
    assert forearm[1] > 0.05  # towards +y (the body's midline) for the right arm
    assert abs(forearm[0]) < 0.005


def _link_of(joint: ET.Element, tag: str) -> str:
    element = joint.find(tag)
    assert element is not None, f"joint {joint.get('name')} has no <{tag}>"
    return element.get("link", "")


def _urdf_chain_positions(q: np.ndarray) -> dict[str, np.ndarray]:
    """World position of every joint frame of the URDF chain from the torso, for joint angles q."""
    root = ET.parse(URDF_PATH).getroot()
    angles = dict(zip(JOINT_NAMES, q, strict=True))
    children = {_link_of(j, "parent"): j for j in root.findall("joint")}
    positions: dict[str, np.ndarray] = {}
    rot, pos = np.eye(3), np.zeros(3)
    link = "torso"
    while link in children:
        joint = children[link]
        origin = joint.find("origin")
        assert origin is not None and origin.get("rpy") == "0 0 0"
        pos = pos + rot @ np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
        positions[joint.get("name", "")] = pos
        if joint.get("type") == "revolute":
            axis_element = joint.find("axis")
            assert axis_element is not None
            axis = np.array([float(v) for v in axis_element.get("xyz", "").split()])
            angle = angles[joint.get("name", "")]
            k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            rot = rot @ (np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k)
        link = _link_of(joint, "child")
    assert list(positions) == [*JOINT_NAMES, "RHandTip"]
    return positions


def test_urdf_chain_matches_forward_kinematics_at_random_poses() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
        fk = forward_kinematics(q)
        urdf = _urdf_chain_positions(q)
        np.testing.assert_allclose(urdf["RShoulderPitch"], fk["shoulder"], atol=1e-9)
        np.testing.assert_allclose(urdf["RElbowYaw"], fk["elbow"], atol=1e-9)
        np.testing.assert_allclose(urdf["RWristYaw"], fk["wrist"], atol=1e-9)
        np.testing.assert_allclose(urdf["RHandTip"], fk["hand"], atol=1e-9)


def test_urdf_limits_match_joint_limits() -> None:
    root = ET.parse(URDF_PATH).getroot()
    for name, (lo, hi) in zip(JOINT_NAMES, JOINT_LIMITS, strict=True):
        joint = root.find(f"joint[@name='{name}']")
        assert joint is not None, name
        limit = joint.find("limit")
        assert limit is not None
        assert float(limit.get("lower", "nan")) == pytest.approx(lo)
        assert float(limit.get("upper", "nan")) == pytest.approx(hi)


def test_ik_recovers_reachable_points_within_1cm_and_within_limits() -> None:
    rng = np.random.default_rng(1)
    errors = []
    for _ in range(30):
        # targets produced by FK from poses near the table workspace are reachable by construction
        q_true = np.clip(
            [0.55, -0.2, 0.9, 0.9, 0.0] + rng.normal(0, 0.25, 5), JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
        )
        target = forward_kinematics(q_true)["hand"]
        q = inverse_kinematics(target)
        assert np.all(q >= JOINT_LIMITS[:, 0]) and np.all(q <= JOINT_LIMITS[:, 1])
        errors.append(np.linalg.norm(forward_kinematics(q)["hand"] - target))
    assert max(errors) < 0.01
    assert np.median(errors) < 0.001


def test_ik_is_deterministic_and_honours_a_fixed_wrist_yaw() -> None:
    target = np.array([0.12, -0.11, -0.03])
    a = inverse_kinematics(target)
    np.testing.assert_array_equal(a, inverse_kinematics(target))
    b = inverse_kinematics(target, wrist_yaw=1.2)
    assert b[4] == pytest.approx(1.2)
    assert np.linalg.norm(forward_kinematics(b)["hand"] - target) < 0.005
