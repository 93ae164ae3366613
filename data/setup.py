"""One recording's setup, apart from the teacher's style (`data.motion.Teacher`) and the camera's look
(`data.camera.Appearance`): the world (table height, where the object stands, its size and form), the
arm (start and rest postures, which of the redundant arm's IK solutions it takes) and how the action
is performed (duration band, phase timing, a pause within the action, the approach path, the manner
within the instruction of Fig. 5b, the direction the object is moved in).

`PAPER_SETUP` is the paper's corpus: one table, one start posture (`HOME_POSTURE`), the arm following
its previous solution, 3-6 s. `data.variety.sample_setup` draws the wide variety's.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from data.nao import HOME_POSTURE, forward_kinematics
from data.world import PAPER_WORLD, World

PHASES = ("reach", "descend", "act", "hold", "back")  # the timeline's segments (data.motion._timeline)
MANNERS = 3  # ways of performing each action within its instruction (0: the paper's)


@dataclass(frozen=True)
class Setup:
    """Everything about a recording's world and arm that the paper keeps fixed; defaults: the paper's."""

    world: World = field(default_factory=World)
    start_posture: tuple[float, ...] = tuple(float(v) for v in HOME_POSTURE)  # joint angles (rad)
    rest_posture: tuple[float, ...] | None = None  # where the arm retreats to; None: the start posture
    posture_family: str = "home"  # a name for the region the start posture was drawn from
    ik_preference: tuple[float, float] | None = None  # (RShoulderRoll, RElbowYaw) the null space pulls to
    duration: tuple[float, float] = (3.0, 6.0)  # the recording's length is clipped to this band (s)
    phases: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 1.0)  # duration factor of each of PHASES
    pause: float = 0.0  # (s) the teacher stops halfway through the action
    approach: tuple[float, float, float] = (0.0, 0.0, 0.0)  # (m) the approach path's detour
    manner: int = 0  # how the action is performed within its instruction, 0..MANNERS-1
    direction: float = 0.0  # (rad) the object's path turned from the instruction's axis
    wrist_speed: float | None = None  # (rad/s) segments last long enough to turn the wrist no faster
    joint_speed: float | None = None  # (rad/s) no joint moves faster (the arm lags the path a moment)

    @property
    def start(self) -> np.ndarray:
        return np.array(self.start_posture)

    @property
    def rest_hand(self) -> np.ndarray:
        """Where the hand retreats towards at the end (torso frame, m)."""
        return forward_kinematics(self.start if self.rest_posture is None else np.array(self.rest_posture))[
            "hand"
        ]

    def ik_anchor(self) -> np.ndarray | None:
        """The posture the IK's null space is pulled to (`inverse_kinematics(preference=...)`), or None."""
        if self.ik_preference is None:
            return None
        roll, yaw = self.ik_preference
        return np.array([0.7, roll, yaw, 0.8, 0.0])

    def to_dict(self) -> dict[str, object]:
        """JSON-friendly form (for corpus metadata)."""
        out = {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items() if k != "world"}
        out["world"] = self.world.to_dict()
        return out

    @classmethod
    def from_dict(cls, values: dict) -> Setup:
        """Inverse of `to_dict`."""
        rest = {k: (tuple(v) if isinstance(v, list) else v) for k, v in values.items() if k != "world"}
        return cls(world=World.from_dict(values["world"]), **rest)


PAPER_SETUP = Setup(world=PAPER_WORLD)
