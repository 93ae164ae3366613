"""Teacher-guided arm motions for the four actions of Fig. 5b, at 20 frames per second.

Workspace (torso frame, metres; x forward, y left, z up; see `data/nao.py`): the robot sits at a
table whose top is `TABLE_Z` = -0.07, i.e. 0.17 m below the right shoulder (0, -0.098, 0.100).
Objects stand on the table in front of the right arm around `OBJECT_HOME` = (0.114, -0.10); a
teacher places them within a few centimetres of it. The NAO's hand reaches between ~0.155 m
(elbow fully bent) and 0.219 m (arm straight) from the shoulder, which at table height is a band
from ~0.05 m to ~0.16 m in front of the shoulder. The guided hand path is kept inside this shell
(`_within_reach`), as a real arm held by a teacher would be.

The teaching instructions (Fig. 5b) become hand paths relative to the object:

    pull     hand over the object to its far side, down, drag it towards the torso (-x)
    push     hand down on the object's near side, push it away from the torso (+x)
    show me  hand moves next to the object (its right side, a little above it) and stops there,
             pointing at it with a small dip; the object stays
    slide    hand down on the object's right (-y) side, slide it horizontally to the left (+y)

All objects have a similar mass and friction, so the path depends on the object only through
its footprint (where the hand makes contact), never on its colour. The one exception the paper
keeps: the long banana is slid with the hand turned (a different wrist yaw), lower and further.

In the paper's setup (`data.setup.PAPER_SETUP`) every recording starts from the same arm posture
(`data.nao.HOME_POSTURE`) at one table and lasts 3-6 s. A `Setup` drawn by the wide variety
(`data.variety`) moves the table, the object and the start and rest postures, pulls the redundant
arm towards another IK solution (elbow high or low), stretches the phases, pauses halfway, detours
the approach and performs the action in another manner within its instruction (`_pull`, `_push`,
`_slide`, `_show`: manner 0 is the paper's). A `Teacher` is a person's style (tempo, amplitude,
approach, hesitation, tremor, placement habits); the per-recording `rng` adds trial-to-trial
variation on top.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from data.nao import (
    JOINT_LIMITS,
    SHOULDER_OFFSET_Y,
    SHOULDER_OFFSET_Z,
    forward_kinematics,
    inverse_kinematics,
)
from data.scenario import Scene
from data.setup import PAPER_SETUP, Setup
from data.world import FPS

MIN_DURATION_S, MAX_DURATION_S = PAPER_SETUP.duration

HAND_RADIUS = 0.013  # half thickness of the NAO hand: hand centre to object surface at contact
FINGER_REACH = 0.022  # pushing, the fingertips touch the object: the hand centre stays this much further

_SHOULDER = np.array([0.0, -SHOULDER_OFFSET_Y, SHOULDER_OFFSET_Z])
_REACH = (0.158, 0.216)  # hand distance from the shoulder the arm can achieve, with a margin (m)

_BANANA_SLIDE_WRIST_YAW = 1.1  # extra wrist yaw (rad) when sliding the long banana
_BANANA_SLIDE_REACH = 1.45  # the banana slide is longer ...
_BANANA_SLIDE_DROP = 0.008  # ... and lower (metres closer to the table)

IK_PULL = 0.015  # null-space gain towards a setup's preferred IK solution, per iteration ...
IK_PULL_STEPS = (
    3  # ... at least this many iterations per frame (the arm settles within 1-2 s, at most 0.15 rad a frame)
)


@dataclass(frozen=True)
class Teacher:
    """One human teacher's style. Draw with `Teacher.sample(rng)`; the ranges are deliberately wide."""

    tempo: float  # > 1 moves faster (shorter phases)
    amplitude: float  # how far the object is moved (m)
    approach_height: float  # lift above the contact height while approaching (m)
    approach_angle: float  # direction the hand comes in from, rotated in the table plane (rad)
    contact_height: float  # hand centre above the table while moving the object (m)
    hesitation: float  # pause before acting (s)
    tremor: float  # hand tremor amplitude (m)
    tremor_hz: float  # dominant tremor frequency (Hz)
    placement: tuple[float, float]  # habitual object offset from OBJECT_HOME (m)
    wrist_yaw: float  # habitual wrist rotation (rad)
    retreat: float  # fraction of the way back to the start posture at the end, 0..1
    point_reach: float  # for show me: how far past the object's near edge the hand stops (m)

    @classmethod
    def sample(cls, rng: np.random.Generator) -> Teacher:
        """A new teacher; four draws behave like four different people, and more."""
        return cls(
            tempo=float(rng.uniform(0.7, 1.45)),
            amplitude=float(rng.uniform(0.03, 0.06)),
            approach_height=float(rng.uniform(0.02, 0.06)),
            approach_angle=float(rng.uniform(-0.5, 0.5)),
            contact_height=float(rng.uniform(0.014, 0.028)),
            hesitation=float(rng.choice([0.0, rng.uniform(0.1, 0.8)])),
            tremor=float(rng.uniform(0.0003, 0.003)),
            tremor_hz=float(rng.uniform(3.0, 9.0)),
            placement=(float(rng.uniform(-0.005, 0.005)), float(rng.uniform(-0.015, 0.015))),
            wrist_yaw=float(rng.uniform(-0.35, 0.35)),
            retreat=float(rng.uniform(0.0, 1.0)),
            point_reach=float(rng.uniform(0.0, 0.025)),
        )

    def to_dict(self) -> dict[str, float | list[float]]:
        """JSON-friendly form (for corpus metadata)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, values: dict) -> Teacher:
        """Inverse of `to_dict`."""
        return cls(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in values.items()})


@dataclass(frozen=True)
class Motion:
    """A recorded manipulation: joint angles, hand path and the object's pose, per frame at `fps`."""

    joints: np.ndarray  # [T, 5] radians, JOINT_NAMES order
    hand: np.ndarray  # [T, 3] hand position reached by the joints (torso frame, m)
    path: np.ndarray  # [T, 3] the hand path the teacher guided (IK target per frame)
    object_xy: np.ndarray  # [T, 2] object centre on the table (torso frame, m)
    object_yaw: np.ndarray  # [T] object rotation about the vertical (rad)
    contact: np.ndarray  # [T] bool, hand is moving the object
    fps: float = FPS

    @property
    def duration(self) -> float:
        return len(self.joints) / self.fps


def _min_jerk(s: np.ndarray) -> np.ndarray:
    """Minimum-jerk time scaling 10s^3 - 15s^4 + 6s^5 (smooth human reaching)."""
    return s**3 * (10 - 15 * s + 6 * s**2)


def _within_reach(points: np.ndarray) -> np.ndarray:
    """Move hand points [n,3] horizontally (height kept) into the shell the arm can reach."""
    rel = points - _SHOULDER
    dz2 = rel[:, 2] ** 2
    horizontal = np.linalg.norm(rel[:, :2], axis=1)
    lo = np.sqrt(np.maximum(_REACH[0] ** 2 - dz2, 0.0))
    hi = np.sqrt(np.maximum(_REACH[1] ** 2 - dz2, 0.0))
    scale = np.clip(horizontal, lo, hi) / np.maximum(horizontal, 1e-9)
    out = points.copy()
    out[:, :2] = _SHOULDER[:2] + rel[:, :2] * scale[:, None]
    return out


def _tremor(n: int, teacher: Teacher, rng: np.random.Generator) -> np.ndarray:
    """[n, 3] tremor: a sinusoid at the teacher's frequency plus smoothed noise."""
    t = np.arange(n) / FPS
    phase = rng.uniform(0, 2 * np.pi, 3)
    wave = np.sin(2 * np.pi * teacher.tremor_hz * t[:, None] + phase[None, :])
    noise = rng.normal(0.0, 1.0, (n + 8, 3))
    kernel = np.hanning(7)
    kernel /= kernel.sum()
    smooth = np.stack([np.convolve(noise[:, k], kernel, mode="same")[4 : 4 + n] for k in range(3)], axis=1)
    return teacher.tremor * (0.6 * wave + 1.2 * smooth)


@dataclass(frozen=True)
class _Approach:
    """What the keyframes of every action are placed from: the object, the teacher's jittered habits."""

    obj: np.ndarray  # object centre (x, y)
    size: tuple[float, float, float]  # the object's half extents and height
    table_z: float
    contact_z: float  # hand height while moving the object
    lift: float  # lift above the contact height while approaching
    over_z: float  # a height that clears the object's top
    side: np.ndarray  # unit vector of the rotated approach direction
    home: np.ndarray  # where the hand starts
    manner: int  # Setup.manner


def _pull(a: _Approach, teacher: Teacher, jitter: Callable[[float], float]) -> tuple:
    """Behind the object (its far side), drag it towards the torso: over it (manner 0, the paper's),
    around its right side (1) or in a high arc down behind it (2)."""
    half_x, half_y, _ = a.size
    c0 = np.array([a.obj[0] + half_x + HAND_RADIUS, a.obj[1] + jitter(0.004), a.contact_z])
    pre = [np.array([c0[0] + 0.01, c0[1] - 0.025 * a.side[1], a.over_z])]  # over the object
    if a.manner == 1:
        pre = [
            np.array([a.obj[0], a.obj[1] - half_y - 0.035, a.contact_z + 0.5 * a.lift]),
            np.array([c0[0] + 0.012, c0[1] - 0.02, a.contact_z + 0.3 * a.lift]),
        ]
    elif a.manner == 2:
        pre = [pre[0] + np.array([0.0, 0.0, 0.03]), np.array([c0[0] + 0.005, c0[1], a.over_z])]
    return np.array([-1.0, 0.0]), c0, pre


def _push(a: _Approach, teacher: Teacher, jitter: Callable[[float], float]) -> tuple:
    """In front of the object (its near side), push it away: coming in low (0, the paper's), down from
    above (1) or low from the right (2)."""
    half_x, _, _ = a.size
    low = min(a.contact_z, a.table_z + 0.014)  # close to the torso the arm only reaches low down
    c0 = np.array([a.obj[0] - half_x - HAND_RADIUS - FINGER_REACH, a.obj[1] + jitter(0.004), low])
    pre = [np.array([c0[0] + 0.015, c0[1] - 0.035 - 0.015 * a.side[1], low + 0.15 * a.lift])]
    if a.manner == 1:
        pre = [np.array([c0[0] - 0.005, c0[1], a.over_z])]
    elif a.manner == 2:
        pre = [np.array([c0[0] - 0.01, c0[1] - 0.055, low + 0.5 * a.lift])]
    return np.array([1.0, 0.0]), c0, pre


def _slide(a: _Approach, teacher: Teacher, jitter: Callable[[float], float]) -> tuple:
    """On the object's right side, slide it to the left: at the teacher's contact height (0, the
    paper's), with the fingertips, higher and further out (1) or coming round from behind it (2)."""
    half_x, half_y, height = a.size
    c0 = np.array([a.obj[0] + 0.01 * a.side[1] + jitter(0.004), a.obj[1] - half_y - HAND_RADIUS, a.contact_z])
    if a.manner == 1:
        c0 += np.array([0.012, -0.008, 0.012])
    pre = [np.array([c0[0] + 0.02 * a.side[0] - 0.01, c0[1] - 0.02, c0[2] + a.lift])]
    if a.manner == 2:
        pre = [
            np.array([a.obj[0] + half_x + 0.03, c0[1] + 0.01, a.over_z]),
            np.array([c0[0] + 0.01, c0[1] - 0.015, c0[2] + 0.5 * a.lift]),
        ]
    return np.array([0.0, 1.0]), c0, pre


def _show(a: _Approach, teacher: Teacher, jitter: Callable[[float], float]) -> tuple:
    """Point at the object, which stays: the hand stops beside and above it on its right (0, the
    paper's), above it (1) or in front of it (2)."""
    half_x, half_y, height = a.size
    top = a.table_z + height
    if a.manner == 1:
        c0 = np.array([a.obj[0] - 0.005, a.obj[1] - 0.008, top + 0.035 + 0.2 * a.lift])
    elif a.manner == 2:
        c0 = np.array(
            [a.obj[0] - half_x - 0.03 - teacher.point_reach, a.obj[1] - 0.005, top + 0.012 + 0.2 * a.lift]
        )
    else:
        c0 = np.array(
            [
                a.obj[0] + teacher.point_reach * 0.5,
                a.obj[1] - min(half_y, 0.025) - 0.012 - teacher.point_reach,  # above a long banana's end
                top + 0.015 + 0.2 * a.lift,
            ]
        )
    pre = [0.5 * (a.home + c0) + np.array([0.0, 0.0, 0.01])]
    return np.zeros(2), c0, pre


_ACTIONS = {"pull": _pull, "push": _push, "slide": _slide, "show me": _show}


def _keyframes(
    scene: Scene, teacher: Teacher, rng: np.random.Generator, obj: np.ndarray, home: np.ndarray, setup: Setup
) -> tuple[list[tuple[np.ndarray, float, float]], tuple[int, int], np.ndarray]:
    """Hand keyframes [(point, duration s, wrist yaw)], the segments [first, last) in which the hand
    moves the object and the direction the object is moved in the table plane."""
    size = setup.world.size(scene.shape)
    table_z = setup.world.table_z

    def jitter(scale: float) -> float:  # trial-to-trial variation of the teacher's habits
        return float(rng.normal(0.0, scale))

    amp = teacher.amplitude * (1.0 + jitter(0.12))
    contact_z = table_z + teacher.contact_height + jitter(0.002)
    lift = teacher.approach_height + jitter(0.005)
    yaw = teacher.wrist_yaw + jitter(0.05)
    ang = teacher.approach_angle + jitter(0.1)
    side = np.array([np.cos(ang), np.sin(ang)])  # unit vector, rotated approach direction
    over_z = table_z + size[2] + 0.02 + lift  # clears the object's top
    approach = _Approach(obj, size, table_z, contact_z, lift, over_z, side, home, setup.manner)
    direction, c0, pre = _ACTIONS[scene.action](approach, teacher, jitter)
    if scene.action == "slide" and scene.shape == "banana":  # the paper's exception: the long banana
        c0[2] -= _BANANA_SLIDE_DROP
        amp *= _BANANA_SLIDE_REACH
        yaw += _BANANA_SLIDE_WRIST_YAW
    if setup.direction != 0.0:
        c, s = np.cos(setup.direction), np.sin(setup.direction)
        direction = np.array([c * direction[0] - s * direction[1], s * direction[0] + c * direction[1]])
    if any(setup.approach):
        pre = [p + np.asarray(setup.approach) for p in pre]
    frames, contact = _timeline(scene, teacher, rng, setup, home, pre, c0, direction, amp, yaw)
    return frames, contact, direction


def _timeline(
    scene: Scene,
    teacher: Teacher,
    rng: np.random.Generator,
    setup: Setup,
    home: np.ndarray,
    pre: list[np.ndarray],
    c0: np.ndarray,
    direction: np.ndarray,
    amp: float,
    yaw: float,
) -> tuple[list[tuple[np.ndarray, float, float]], tuple[int, int]]:
    """The keyframes from home over `pre` to the contact point `c0`, the action (the object moved `amp`
    along `direction` in the table plane, with the setup's pause halfway, or the pointing dip) and back
    towards the rest posture, timed by the teacher's tempo and the setup's phases; and the segments
    [first, last) that move the object (first == last: none)."""
    tempo = teacher.tempo * (1.0 + float(rng.normal(0.0, 0.08)))
    reach_s, descend_s, act_s, hold_s, back_s = (
        np.array([1.1, 0.45, 1.2, 0.25, 0.8]) / tempo * np.array(setup.phases)
    )
    act_s *= 0.6 + amp / 0.045 * 0.4
    pause_s = teacher.hesitation * (1.0 + float(rng.normal(0.0, 0.2))) if teacher.hesitation > 0 else 0.0
    idle_s = float(rng.uniform(0.1, 0.4))
    end = c0.copy()
    end[:2] += direction * amp
    back = end + (setup.rest_hand - end) * teacher.retreat * 0.8
    back[2] = max(back[2], end[2] + 0.02)
    frames: list[tuple[np.ndarray, float, float]] = [(home, idle_s, float(setup.start_posture[4]))]
    frames += [(p, reach_s / len(pre), yaw) for p in pre]
    frames.append((c0, descend_s, yaw))
    if pause_s > 0:
        frames.append((c0 + np.array([0.0, 0.0, 0.002]), pause_s, yaw))
    first = len(frames) - 1
    if scene.action == "show me":  # the pointing gesture: a small dip towards the object, then hold
        frames.append((c0 + np.array([0.002, 0.008, -0.01]), act_s * 0.6, yaw))
        contact = (first, first)
    elif setup.pause > 0:  # the teacher stops halfway, the hand still on the object
        middle = 0.5 * (c0 + end)
        frames += [(middle, act_s * 0.5, yaw), (middle, setup.pause, yaw), (end, act_s * 0.5, yaw)]
        contact = (first, first + 3)
    else:
        frames.append((end, act_s, yaw))
        contact = (first, first + 1)
    frames.append((frames[-1][0], hold_s, yaw))
    final_yaw = teacher.wrist_yaw if setup.rest_posture is None else setup.rest_posture[4]
    frames.append((back, back_s, final_yaw))
    if setup.wrist_speed is not None:
        speed = setup.wrist_speed
        frames[1:] = [(p, max(d, abs(w - frames[i][2]) / speed), w) for i, (p, d, w) in enumerate(frames[1:])]
    return frames, contact


def _hand_path(
    frames: list[tuple[np.ndarray, float, float]], setup: Setup
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Times [n], the minimum-jerk hand path [n,3] and wrist yaw [n] through the keyframes, and the
    keyframe segment of every frame [n] (-1: before the first), the length clipped to the setup's band."""
    durations = np.array([d for _, d, _ in frames[1:]])
    total = float(np.clip(durations.sum() + frames[0][1], *setup.duration))
    durations *= (total - frames[0][1]) / durations.sum()
    n = int(round(total * FPS))

    t = np.arange(n) / FPS
    bounds = frames[0][1] + np.concatenate([[0.0], np.cumsum(durations)])
    hand = np.empty((n, 3))
    wrist = np.empty(n)
    segment = np.clip(np.searchsorted(bounds, t, side="right") - 1, -1, len(durations) - 1)
    for i in range(n):
        k = segment[i]
        if k < 0:
            hand[i], wrist[i] = frames[0][0], frames[0][2]
            continue
        s = _min_jerk(np.clip((t[i] - bounds[k]) / durations[k], 0.0, 1.0))
        (p0, _, w0), (p1, _, w1) = frames[k], frames[k + 1]
        hand[i] = p0 + s * (p1 - p0)
        wrist[i] = w0 + s * (w1 - w0)
    return t, hand, wrist, segment


def _joints(hand: np.ndarray, wrist: np.ndarray, setup: Setup) -> np.ndarray:
    """Joint angles [n,5] reaching the hand path frame by frame from the start posture, each solved
    from the previous frame's solution (and pulled towards the setup's preferred solution, if any)."""
    anchor = setup.ik_anchor()
    pull = (
        {}
        if anchor is None
        else {"preference": anchor, "posture_gain": IK_PULL, "min_iterations": IK_PULL_STEPS}
    )
    joints = np.empty((len(hand), 5))
    q = setup.start.copy()
    for i in range(len(hand)):
        solved = inverse_kinematics(hand[i], q0=q, wrist_yaw=float(wrist[i]), **pull)
        if setup.joint_speed is not None:  # where the solution flips at a joint limit, the arm lags
            step = setup.joint_speed / FPS
            solved = q + np.clip(solved - q, -step, step)
        q = solved
        joints[i] = q
    return joints


def generate_motion(
    scene: Scene, teacher: Teacher, rng: np.random.Generator, setup: Setup = PAPER_SETUP
) -> Motion:
    """The arm motion of one recording of `scene` taught by `teacher` in `setup` (the paper's by
    default: 3-6 s at 20 fps from `HOME_POSTURE`).

    The hand path is a chain of minimum-jerk segments between keyframes placed relative to the
    object, plus tremor; each frame is solved by inverse kinematics from the previous frame's
    solution (smooth joints within `JOINT_LIMITS`). The object moves with the hand while in
    contact, only along the action's direction (it is pushed, pulled, slid; never lifted).
    """
    world = setup.world
    obj0 = np.asarray(world.object_home) + np.asarray(teacher.placement) + rng.normal(0.0, [0.003, 0.006])
    yaw0 = float(rng.normal(0.0, 0.25))
    home = forward_kinematics(setup.start)["hand"]
    frames, (first, last), direction = _keyframes(scene, teacher, rng, obj0, home, setup)
    t, hand, wrist, segment = _hand_path(frames, setup)
    n = len(t)
    contact = (segment >= first) & (segment < last)
    hand = hand + _tremor(n, teacher, rng) * np.clip(t / 0.5, 0.0, 1.0)[:, None]
    hand[:, 2] = np.maximum(hand[:, 2], world.table_z + 0.006)
    hand = _within_reach(hand)
    joints = _joints(hand, wrist, setup)
    reached = np.array([forward_kinematics(qi)["hand"] for qi in joints])

    # the object follows the hand's progress along the action's direction while in contact
    progress = np.where(contact, (reached[:, :2] - reached[np.argmax(contact), :2]) @ direction, 0.0)
    pushed = np.maximum.accumulate(np.maximum(progress, 0.0)) if contact.any() else np.zeros(n)
    drift = float(rng.normal(0.0, 0.12))  # objects never move perfectly straight
    perpendicular = np.array([-direction[1], direction[0]])
    object_xy = obj0 + pushed[:, None] * (direction + drift * perpendicular)[None, :]
    object_yaw = yaw0 + pushed * float(rng.normal(0.0, 2.0))
    return Motion(
        joints=np.clip(joints, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]),
        hand=reached,
        path=hand,
        object_xy=object_xy,
        object_yaw=object_yaw,
        contact=contact,
    )


def retimed(motion: Motion, slower: float, fps: float | None = None) -> Motion:
    """The motion played `slower` times slower (< 1: faster) and sampled at `fps` Hz (default: its
    own rate): joints, hand, path and object pose interpolated linearly between the taught frames."""
    fps = motion.fps if fps is None else fps
    n = len(motion.joints)
    rate = fps / motion.fps  # samples per taught frame at the taught speed
    steps = max(2, int(round(n * slower * rate)))
    taught = np.minimum(np.arange(steps) / rate / slower, n - 1)  # taught frame index of each sample
    frames = np.arange(n)

    def interp(values: np.ndarray) -> np.ndarray:
        flat = values.reshape(n, -1)
        out = np.stack([np.interp(taught, frames, flat[:, j]) for j in range(flat.shape[1])], axis=1)
        return out.reshape((steps, *values.shape[1:]))

    return Motion(
        joints=interp(motion.joints),
        hand=interp(motion.hand),
        path=interp(motion.path),
        object_xy=interp(motion.object_xy),
        object_yaw=interp(motion.object_yaw),
        contact=motion.contact[np.round(taught).astype(int)],
        fps=fps,
    )
