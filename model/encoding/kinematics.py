"""The hand's path read from joint codes through an arm's published kinematic chain.

The paper's MTRNN_s reads the five joint angles (4.1.1). The same hand path can be reached with
other joint configurations (the NAO arm is redundant: shoulder roll and elbow yaw trade off), so
the angles also tell *how this teacher held the arm*, which other robots and simulators do
differently. The hand's path in the torso frame does not depend on that choice: end_to_end's
option `hand_path` gives MTRNN_s the joint codes and, beside them, the hand's position relative to
where it started and its displacement per step, both computed here by forward kinematics.

`ArmChain` is what that needs of a robot, as plain numbers (`model/` knows no robot; the NAO's
published chain is `data.nao.NAO_ARM`, passed in as the encoders are passed joint limits): per
joint its origin offset from the previous joint frame and its rotation axis, the hand's offset from
the last joint frame, and the joint limits that decode the [0, 1] codes (`proprioception.py`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import torch
from torch import Tensor

HAND_PATH_COLUMNS = 6  # position relative to the start (3), displacement per step (3)
# Displacement per step is ~1 % of the reach (20 Hz); this gain brings it to the position's order.
STEP_GAIN = 10.0


@dataclass(frozen=True)
class ArmChain:
    """A serial arm of revolute joints (module docstring); lengths in metres, angles in radians."""

    origins: tuple[tuple[float, float, float], ...]  # [J, 3] each joint's offset in the previous frame
    axes: tuple[tuple[float, float, float], ...]  # [J, 3] unit rotation axes
    hand_offset: tuple[float, float, float]  # the hand in the last joint's frame
    limits: tuple[tuple[float, float], ...]  # [J, 2] (min, max), the codes' range

    def __post_init__(self) -> None:
        joints = len(self.axes)
        if joints == 0 or len(self.origins) != joints or len(self.limits) != joints:
            raise ValueError("an arm needs one origin, axis and limit pair per joint")
        if len(self.hand_offset) != 3 or any(len(v) != 3 for v in (*self.origins, *self.axes)):
            raise ValueError("origins, axes and the hand offset are 3-vectors")
        if any(hi <= lo for lo, hi in self.limits):
            raise ValueError("every joint limit needs min < max")

    @property
    def joints(self) -> int:
        return len(self.axes)

    @property
    def reach(self) -> float:
        """Sum of the link lengths: the scale of the hand-path columns."""
        return sum(math.hypot(*o) for o in self.origins[1:]) + math.hypot(*self.hand_offset)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> ArmChain:
        def rows(key: str) -> tuple:
            return tuple(tuple(float(x) for x in row) for row in d[key])

        return cls(rows("origins"), rows("axes"), tuple(float(x) for x in d["hand_offset"]), rows("limits"))


def _skew(axis: Tensor) -> Tensor:
    x, y, z = axis.tolist()
    return torch.tensor([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def hand_positions(angles: Tensor, arm: ArmChain) -> Tensor:
    """Forward kinematics: joint angles [..., J] (radians) -> hand positions [..., 3] (metres)."""
    rot = torch.eye(3).expand(*angles.shape[:-1], 3, 3)
    pos = torch.zeros(*angles.shape[:-1], 3)
    for i in range(arm.joints):
        pos = pos + rot @ torch.tensor(arm.origins[i])
        k = _skew(torch.tensor(arm.axes[i]))
        s, c = torch.sin(angles[..., i])[..., None, None], torch.cos(angles[..., i])[..., None, None]
        rot = rot @ (torch.eye(3) + s * k + (1 - c) * (k @ k))  # Rodrigues' rotation about axis i
    return pos + rot @ torch.tensor(arm.hand_offset)


def read_hand_path(codes: Tensor, arm: ArmChain) -> Tensor:
    """Joint codes [B, T, J] in [0, 1] -> [B, T, J + 6]: the codes, the hand's position relative to
    its first step over the reach, and its displacement per step over the reach times `STEP_GAIN`
    (zero at the first step). Steps past a sequence's end are the caller's padding; MTRNN_s stops
    reading at each sequence's length, so what they give here is never read."""
    limits = torch.tensor(arm.limits)
    angles = limits[:, 0] + codes * (limits[:, 1] - limits[:, 0])
    hand = hand_positions(angles, arm)
    relative = (hand - hand[:, :1]) / arm.reach
    step = torch.zeros_like(hand)
    step[:, 1:] = (hand[:, 1:] - hand[:, :-1]) * (STEP_GAIN / arm.reach)
    return torch.cat([codes, relative, step], dim=-1)
