"""How varied a corpus is: "paper" (today's sampling, the paper's one table, posture and IK solution)
or "wide" (every setup parameter over its plausible range), drawn per recording from the streams
`data.corpus` derives from (seed, scene.index, variant).

The wide variety (issue 12) draws, from a fourth stream, a `Setup`:

- the table top anywhere in `TABLE_BAND` (the band the hand can work in: lower, and the hand barely
  reaches past the object's near side; higher, and it cannot get close to the torso), the object
  anywhere on the annulus the hand reaches at that height (`placement`), on both sides of the
  straight-ahead line of the shoulder (`AZIMUTH`), which spans both sides of the arm's home;
- start and rest postures drawn within the joint limits, in one of four families
  (`POSTURE_FAMILIES`: the hand raised or low, out to the right or in front);
- a preferred IK solution (shoulder roll, elbow yaw: negative yaw lifts the elbow, positive
  lowers it), which the redundant arm's null space is pulled towards frame by frame;
- the teacher's tempo (recordings of 2-8 s), each phase's length, a pause halfway through the
  action, a detour on the approach, one of `data.setup.MANNERS` manners per action and the
  direction the object is moved in turned by up to 0.25 rad (all within Fig. 5b's instructions);
- the object's size (+-25 %) and form (dice sharp or rounded, with or without pips; apple with or
  without stem; banana straight to strongly curved; phone screen dark, light or none, thin or thick);
- the camera's height, aim (tilt), roll and field of view wider than the paper's; light, table and
  sensor as the paper's.

`labels` names the regions of this space a recording lies in, for leave-one-setup-out splits.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from data.camera import Appearance, head_angles
from data.camera.camera import HEAD_ORIGIN
from data.motion import Teacher
from data.nao import JOINT_LIMITS, SHOULDER_OFFSET_Y, SHOULDER_OFFSET_Z, forward_kinematics
from data.scenario import Scene
from data.setup import MANNERS, PAPER_SETUP, Setup
from data.world import FPS, PHONE_SCREENS, World

VARIETIES: tuple[str, ...] = ("paper", "wide")

TABLE_BAND = (-0.10, -0.03)  # table top, torso frame (m); the paper's is -0.07
AZIMUTH = (-0.8, 0.55)  # object direction from the shoulder (rad, positive to the left)
WIDE_DURATION = (2.0, 8.0)  # (s)
WIDE_TEMPO = (0.45, 2.0)  # the teacher's tempo, log-uniform (the paper's 0.7-1.45)
POSTURE_FAMILIES: tuple[str, ...] = ("raised-out", "raised-front", "low-out", "low-front")
IK_ELBOW_YAW = (-1.6, 1.6)  # usable preferred RElbowYaw (rad): the null space spans about -2..2
IK_SHOULDER_ROLL = (-0.9, 0.2)  # preferred RShoulderRoll (rad)
WRIST_SPEED = 3.0  # (rad/s) a teacher turns the NAO's wrist no faster on average over a segment
JOINT_SPEED = 5.0  # (rad/s) no joint of a guided arm moves faster (the NAO's motors reach about 7)

_SHOULDER = np.array([0.0, -SHOULDER_OFFSET_Y, SHOULDER_OFFSET_Z])
_REACH = (0.158, 0.216)  # hand distance from the shoulder the arm achieves (data.motion)


def placement(rng: np.random.Generator, table_z: float) -> tuple[float, float]:
    """An object position on the annulus the hand reaches just above a table at `table_z`."""
    dz = _SHOULDER[2] - (table_z + 0.02)
    inner = np.sqrt(max(_REACH[0] ** 2 - dz**2, 0.0))
    outer = np.sqrt(_REACH[1] ** 2 - dz**2)
    lo, hi = max(inner + 0.015, 0.07), outer - 0.02
    radius = float(rng.uniform(lo, hi)) if hi > lo else 0.5 * (lo + hi)
    azimuth = float(rng.uniform(*AZIMUTH))
    x = max(radius * np.cos(azimuth), 0.065)  # never inside the torso
    return float(x), float(_SHOULDER[1] + radius * np.sin(azimuth))


def posture_family(hand: np.ndarray, table_z: float) -> str:
    """The family of a posture from its hand position: raised (10 cm or more above the table) or
    low, out to the right (right of y = -0.16) or in front."""
    height = "raised" if hand[2] > table_z + 0.10 else "low"
    return f"{height}-{'out' if hand[1] < -0.16 else 'front'}"


def posture(rng: np.random.Generator, family: str, table_z: float) -> tuple[float, ...]:
    """Joint angles drawn uniformly within the joint limits whose hand lies in `family`, above the
    table and in front of the torso (rejection sampling; the paper's home posture if none is found)."""
    for _ in range(400):
        q = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
        q[0] = rng.uniform(-0.3, 1.6)  # shoulder pitch: the arm in front, neither up nor behind
        q[4] = rng.uniform(-1.0, 1.0)  # wrist yaw: a hand held by a teacher is not twisted far
        points = forward_kinematics(q)
        hand = points["hand"]
        clear = hand[2] > table_z + 0.04 and points["elbow"][2] > table_z + 0.03
        in_front = hand[0] > 0.05 and -0.30 < hand[1] < 0.0 and hand[2] < 0.2
        if clear and in_front and posture_family(hand, table_z) == family:
            return tuple(float(v) for v in q)
    return PAPER_SETUP.start_posture


def sample_world(rng: np.random.Generator) -> World:
    """Table height, placement, size and the object's form, each over its plausible range."""
    table_z = float(rng.uniform(*TABLE_BAND))
    return World(
        table_z=table_z,
        object_home=placement(rng, table_z),
        size_scale=float(rng.uniform(0.75, 1.25)),
        phone_thickness=float(rng.uniform(0.007, 0.016)),
        phone_screen=str(rng.choice(PHONE_SCREENS)),
        dice_round=float(rng.uniform(0.2, 0.6)) if rng.random() < 0.5 else 0.0,
        apple_stem=bool(rng.random() < 0.5),
    )


def sample_setup(rng: np.random.Generator) -> Setup:
    """A wide setup (module docstring)."""
    world = sample_world(rng)
    family = str(rng.choice(POSTURE_FAMILIES))
    start = posture(rng, family, world.table_z)
    rest = posture(rng, str(rng.choice(POSTURE_FAMILIES)), world.table_z)
    return Setup(
        world=world,
        start_posture=start,
        rest_posture=rest,
        posture_family=posture_family(forward_kinematics(np.array(start))["hand"], world.table_z),
        ik_preference=(float(rng.uniform(*IK_SHOULDER_ROLL)), float(rng.uniform(*IK_ELBOW_YAW))),
        duration=WIDE_DURATION,
        phases=tuple(float(v) for v in rng.uniform(0.6, 1.6, 5)),
        pause=float(rng.uniform(0.2, 1.0)) if rng.random() < 0.35 else 0.0,
        approach=tuple(float(v) for v in rng.normal(0.0, [0.015, 0.015, 0.01])),
        manner=int(rng.integers(0, MANNERS)),
        direction=float(rng.uniform(-0.25, 0.25)),
        wrist_speed=WRIST_SPEED,
        joint_speed=JOINT_SPEED,
    )


def sample_teacher(rng: np.random.Generator) -> Teacher:
    """A teacher as the paper's corpus draws one, at a tempo from the wide range."""
    teacher = Teacher.sample(rng)
    tempo = float(np.exp(rng.uniform(np.log(WIDE_TEMPO[0]), np.log(WIDE_TEMPO[1]))))
    return dataclasses.replace(teacher, tempo=tempo)


def sample_appearance(rng: np.random.Generator, world: World) -> Appearance:
    """Light, table and sensor as the paper's corpus draws them; the camera's height (-3..+6 cm), aim
    (+-3 cm around the object, +-0.08 rad of tilt), roll (+-0.12 rad) and field of view (45-75 degrees)
    wider; the object's proportions are the world's (scale 1), the banana's bend 4-40 mm, the dice
    without pips in 40 % of recordings."""
    app = Appearance.sample(rng)
    offset = tuple(float(v) for v in rng.uniform([-0.03, -0.03, -0.03], [0.03, 0.03, 0.06]))
    aim = np.array([*(np.asarray(world.object_home) + rng.uniform(-0.03, 0.03, 2)), world.table_z])
    yaw, pitch = head_angles(aim, offset)  # type: ignore[arg-type]
    return dataclasses.replace(
        app,
        hfov=float(np.deg2rad(rng.uniform(45.0, 75.0))),
        head_yaw=yaw,
        head_pitch=pitch + float(rng.uniform(-0.08, 0.08)),
        camera_roll=float(rng.uniform(-0.12, 0.12)),
        camera_offset=offset,
        object_scale=1.0,
        banana_bend=float(rng.uniform(0.004, 0.04)),
        dice_pips=int(rng.integers(1, 7)) if rng.random() < 0.6 else 0,
    )


def labels(scene: Scene, setup: Setup, teacher: Teacher, appearance: Appearance, steps: int) -> dict:
    """The regions a recording lies in, by name and number (for held-out regions)."""
    world = setup.world
    roll, elbow_yaw = setup.ik_preference or (PAPER_SETUP.start_posture[1], PAPER_SETUP.start_posture[2])
    return {
        "table_z": round(world.table_z, 4),
        "object_x": round(world.object_home[0], 4),
        "object_y": round(world.object_home[1], 4),
        "posture_family": setup.posture_family,
        "ik_shoulder_roll": round(roll, 4),
        "ik_elbow_yaw": round(elbow_yaw, 4),
        "elbow": "high" if elbow_yaw < -0.5 else ("low" if elbow_yaw > 0.5 else "middle"),
        "tempo": round(teacher.tempo, 4),
        "duration_s": round(steps / FPS, 2),
        "manner": setup.manner,
        "form": world.form(scene.shape, appearance.banana_bend, appearance.dice_pips),
        "size_scale": round(world.size_scale, 4),
        "camera_height": round(float(HEAD_ORIGIN[2] + appearance.camera_offset[2]), 4),
        "camera_pitch": round(appearance.head_pitch, 4),
        "camera_roll": round(appearance.camera_roll, 4),
        "hfov_deg": round(float(np.rad2deg(appearance.hfov)), 2),
    }
