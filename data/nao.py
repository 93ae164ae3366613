"""The NAO (V5 / H25) right arm: joint names and limits, forward and inverse kinematics, URDF.

Frames follow Aldebaran's convention: the torso frame has x forward, y to the robot's left and
z up; lengths are the published NAO V5 link lengths (metres), limits the published joint ranges
(radians). The chain, from the torso:

    RShoulderPitch  at (0, -ShoulderOffsetY, ShoulderOffsetZ), axis y  (positive: arm down)
    RShoulderRoll   same origin,                                 axis z  (positive: towards the body)
    RElbowYaw       at (UpperArmLength, -ElbowOffsetY, 0),        axis x
    RElbowRoll      same origin,                                 axis z  (positive: elbow bent)
    RWristYaw       at (LowerArmLength, 0, 0),                    axis x
    hand            at (HandOffsetX, 0, -HandOffsetZ)

At q = 0 the arm points straight forward. `URDF_PATH` describes the same chain with primitive
geometry; `tests/data/test_nao.py` checks that both agree.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from model.encoding.kinematics import ArmChain

JOINT_NAMES: tuple[str, ...] = ("RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll", "RWristYaw")

# Published NAO V5 ranges of the right-arm joints (radians), one row [min, max] per joint.
JOINT_LIMITS: np.ndarray = np.array(
    [
        [-2.0857, 2.0857],  # RShoulderPitch
        [-1.3265, 0.3142],  # RShoulderRoll
        [-2.0857, 2.0857],  # RElbowYaw
        [0.0349, 1.5446],  # RElbowRoll
        [-1.8238, 1.8238],  # RWristYaw
    ]
)
JOINT_LIMITS.setflags(write=False)

# Published NAO V5 link lengths (metres).
SHOULDER_OFFSET_Y = 0.098
SHOULDER_OFFSET_Z = 0.100
UPPER_ARM_LENGTH = 0.105
ELBOW_OFFSET_Y = 0.015
LOWER_ARM_LENGTH = 0.05595
HAND_OFFSET_X = 0.05775
HAND_OFFSET_Z = 0.01231

URDF_PATH: Path = Path(__file__).resolve().parent / "nao_right_arm.urdf"

# One row per joint: origin offset from the previous joint frame (metres) and rotation axis.
_JOINT_ORIGINS = np.array(
    [
        [0.0, -SHOULDER_OFFSET_Y, SHOULDER_OFFSET_Z],
        [0.0, 0.0, 0.0],
        [UPPER_ARM_LENGTH, -ELBOW_OFFSET_Y, 0.0],
        [0.0, 0.0, 0.0],
        [LOWER_ARM_LENGTH, 0.0, 0.0],
    ]
)
_JOINT_AXES = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
_HAND_OFFSET = np.array([HAND_OFFSET_X, 0.0, -HAND_OFFSET_Z])

# The same chain as numbers, for readings of the hand's path (`model.encoding.kinematics`).
NAO_ARM = ArmChain(
    origins=tuple(tuple(float(x) for x in row) for row in _JOINT_ORIGINS),
    axes=tuple(tuple(float(x) for x in row) for row in _JOINT_AXES),
    hand_offset=tuple(float(x) for x in _HAND_OFFSET),
    limits=tuple(tuple(float(x) for x in row) for row in JOINT_LIMITS),
)

# A comfortable posture (hand in front, above the table) that IK is gently pulled towards.
REST_POSTURE: np.ndarray = np.array([0.6, -0.15, 0.9, 0.9, 0.0])
REST_POSTURE.setflags(write=False)


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix about a unit axis (Rodrigues)."""
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def _chain(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint origins [5,3], world joint axes [5,3] and hand position [3] for angles q."""
    origins, axes, hand, _ = _chain_with_rotation(q)
    return origins, axes, hand


def _chain_with_rotation(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`_chain` plus the orientation [3,3] of the hand (the frame after RWristYaw)."""
    rot = np.eye(3)
    pos = np.zeros(3)
    origins = np.empty((5, 3))
    axes = np.empty((5, 3))
    for i in range(5):
        pos = pos + rot @ _JOINT_ORIGINS[i]
        origins[i] = pos
        axes[i] = rot @ _JOINT_AXES[i]
        rot = rot @ _rotation(_JOINT_AXES[i], float(q[i]))
    return origins, axes, pos + rot @ _HAND_OFFSET, rot


def _check_q(q: np.ndarray | list[float]) -> np.ndarray:
    arr = np.asarray(q, dtype=float)
    if arr.shape != (5,):
        raise ValueError(f"expected 5 joint angles {JOINT_NAMES}, got shape {arr.shape}")
    return arr


def forward_kinematics(q: np.ndarray | list[float]) -> dict[str, np.ndarray]:
    """Positions (metres, torso frame) of shoulder, elbow, wrist and hand for joint angles q [5]."""
    origins, _, hand = _chain(_check_q(q))
    return {"shoulder": origins[0], "elbow": origins[2], "wrist": origins[4], "hand": hand}


def arm_pose(q: np.ndarray | list[float]) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """`forward_kinematics` and the hand's orientation [3,3] (columns: the hand's x, y, z axes)."""
    origins, _, hand, rot = _chain_with_rotation(_check_q(q))
    return {"shoulder": origins[0], "elbow": origins[2], "wrist": origins[4], "hand": hand}, rot


def forward_kinematics_batch(joints: np.ndarray) -> dict[str, np.ndarray]:
    """`forward_kinematics` over a trajectory [T,5]: each entry is [T,3]."""
    per_step = [forward_kinematics(q) for q in np.asarray(joints, dtype=float)]
    return {key: np.stack([p[key] for p in per_step]) for key in ("shoulder", "elbow", "wrist", "hand")}


def inverse_kinematics(
    target_xyz: np.ndarray | list[float],
    q0: np.ndarray | list[float] | None = None,
    wrist_yaw: float | None = None,
    damping: float = 0.02,
    posture_gain: float = 0.02,
    max_iterations: int = 300,
    tolerance: float = 1e-4,
    preference: np.ndarray | None = None,
    min_iterations: int = 0,
) -> np.ndarray:
    """Joint angles [5] that put the hand at `target_xyz` (metres, torso frame).

    Damped least squares, dq = J^T (J J^T + damping^2 I)^-1 e, started from `q0` (default:
    `REST_POSTURE`), clipped to `JOINT_LIMITS` after every step. The redundancy (5 joints, 3
    coordinates) is resolved by a small null-space pull towards `q0`, so consecutive targets
    solved from the previous solution give a smooth trajectory; or, if `preference` [5] is given,
    towards that posture during the first `min_iterations` steps of every call (then the hand task
    alone converges), so that a trajectory solved frame by frame settles into the preferred
    solution (e.g. elbow high or low). `wrist_yaw`, if
    given, fixes RWristYaw and the other four joints reach the target. Deterministic.
    """
    target = np.asarray(target_xyz, dtype=float)
    if target.shape != (3,):
        raise ValueError(f"target must be a 3-D point, got shape {target.shape}")
    start = REST_POSTURE.copy() if q0 is None else _check_q(q0).copy()
    q = np.clip(start, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
    active = np.ones(5, dtype=bool)
    if wrist_yaw is not None:
        q[4] = np.clip(wrist_yaw, JOINT_LIMITS[4, 0], JOINT_LIMITS[4, 1])
        active[4] = False
    anchor = q.copy() if preference is None else _check_q(preference)
    for iteration in range(max_iterations):
        origins, axes, hand = _chain(q)
        error = target - hand
        if iteration >= min_iterations and np.linalg.norm(error) < tolerance:
            break
        jac = np.cross(axes, hand - origins).T[:, active]  # [3, n_active], revolute joints
        jjt = jac @ jac.T + damping**2 * np.eye(3)
        step = jac.T @ np.linalg.solve(jjt, error)
        # null-space projection of the posture pull keeps the hand task first
        null = np.eye(jac.shape[1]) - jac.T @ np.linalg.solve(jjt, jac)
        pull = posture_gain if preference is None or iteration < min_iterations else 0.0
        step = step + pull * null @ (anchor - q)[active]
        q[active] = np.clip(q[active] + step, JOINT_LIMITS[active, 0], JOINT_LIMITS[active, 1])
    return q


# Posture every paper recording starts from (hand raised to the right, above the table's near edge).
HOME_POSTURE: np.ndarray = inverse_kinematics(np.array([0.15, -0.17, 0.0]))
HOME_POSTURE.setflags(write=False)
