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

Every recording starts from the same arm posture (`HOME_POSTURE`), as in the paper. A `Teacher`
is a person's style (tempo, amplitude, approach, hesitation, tremor, placement habits); the
per-recording `rng` adds trial-to-trial variation on top.
"""

from __future__ import annotations

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
from data.world import FPS, OBJECT_HOME, OBJECT_SIZE, TABLE_Z

MIN_DURATION_S = 3.0
MAX_DURATION_S = 6.0

HAND_RADIUS = 0.013  # half thickness of the NAO hand: hand centre to object surface at contact
FINGER_REACH = 0.022  # pushing, the fingertips touch the object: the hand centre stays this much further


# Posture every recording starts from (hand raised to the right, above the table's near edge).
HOME_POSTURE: np.ndarray = inverse_kinematics(np.array([0.15, -0.17, 0.0]))
HOME_POSTURE.setflags(write=False)

_SHOULDER = np.array([0.0, -SHOULDER_OFFSET_Y, SHOULDER_OFFSET_Z])
_REACH = (0.158, 0.216)  # hand distance from the shoulder the arm can achieve, with a margin (m)

_BANANA_SLIDE_WRIST_YAW = 1.1  # extra wrist yaw (rad) when sliding the long banana
_BANANA_SLIDE_REACH = 1.45  # the banana slide is longer ...
_BANANA_SLIDE_DROP = 0.008  # ... and lower (metres closer to the table)


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


def _keyframes(
    scene: Scene, teacher: Teacher, rng: np.random.Generator, obj: np.ndarray, home: np.ndarray
) -> tuple[list[tuple[np.ndarray, float, float]], int, np.ndarray]:
    """Hand keyframes [(point, duration s, wrist yaw)], the index of the keyframe that ends the
    contact segment (-1: no contact) and the direction the object is moved in the table plane."""
    half_x, half_y, height = OBJECT_SIZE[scene.shape]

    def jitter(scale: float) -> float:  # trial-to-trial variation of the teacher's habits
        return float(rng.normal(0.0, scale))

    amp = teacher.amplitude * (1.0 + jitter(0.12))
    contact_z = TABLE_Z + teacher.contact_height + jitter(0.002)
    lift = teacher.approach_height + jitter(0.005)
    yaw = teacher.wrist_yaw + jitter(0.05)
    ang = teacher.approach_angle + jitter(0.1)
    side = np.array([np.cos(ang), np.sin(ang)])  # unit vector, rotated approach direction
    over_z = TABLE_Z + height + 0.02 + lift  # clears the object's top

    if scene.action == "pull":
        direction = np.array([-1.0, 0.0])
        c0 = np.array([obj[0] + half_x + HAND_RADIUS, obj[1] + jitter(0.004), contact_z])
        pre = [np.array([c0[0] + 0.01, c0[1] - 0.025 * side[1], over_z])]  # over the object
    elif scene.action == "push":
        direction = np.array([1.0, 0.0])
        low = min(contact_z, TABLE_Z + 0.014)  # close to the torso the arm only reaches low down
        c0 = np.array([obj[0] - half_x - HAND_RADIUS - FINGER_REACH, obj[1] + jitter(0.004), low])
        pre = [np.array([c0[0] + 0.015, c0[1] - 0.035 - 0.015 * side[1], low + 0.15 * lift])]
    elif scene.action == "slide":
        direction = np.array([0.0, 1.0])
        c0 = np.array([obj[0] + 0.01 * side[1] + jitter(0.004), obj[1] - half_y - HAND_RADIUS, contact_z])
        if scene.shape == "banana":  # the paper's exception: the long banana is slid differently
            c0[2] -= _BANANA_SLIDE_DROP
            amp *= _BANANA_SLIDE_REACH
            yaw += _BANANA_SLIDE_WRIST_YAW
        pre = [np.array([c0[0] + 0.02 * side[0] - 0.01, c0[1] - 0.02, contact_z + lift])]
    else:  # show me: the hand stops just beside and above the object (its right), pointing at it
        direction = np.zeros(2)
        c0 = np.array(
            [
                obj[0] + teacher.point_reach * 0.5,
                obj[1] - min(half_y, 0.025) - 0.012 - teacher.point_reach,  # above a long banana's end
                TABLE_Z + height + 0.015 + 0.2 * lift,
            ]
        )
        pre = [0.5 * (home + c0) + np.array([0.0, 0.0, 0.01])]

    frames, contact_index = _timeline(scene, teacher, rng, home, pre, c0, direction, amp, yaw)
    return frames, contact_index, direction


def _timeline(
    scene: Scene,
    teacher: Teacher,
    rng: np.random.Generator,
    home: np.ndarray,
    pre: list[np.ndarray],
    c0: np.ndarray,
    direction: np.ndarray,
    amp: float,
    yaw: float,
) -> tuple[list[tuple[np.ndarray, float, float]], int]:
    """The keyframes from home over `pre` to the contact point `c0`, the action (the object moved `amp`
    along `direction` in the table plane, or the pointing dip) and back, timed by the teacher's tempo; and the
    index of the keyframe that ends the contact segment (-1: none)."""
    tempo = teacher.tempo * (1.0 + float(rng.normal(0.0, 0.08)))
    reach_s, descend_s, act_s, hold_s, back_s = np.array([1.1, 0.45, 1.2, 0.25, 0.8]) / tempo
    act_s *= 0.6 + amp / 0.045 * 0.4
    pause_s = teacher.hesitation * (1.0 + float(rng.normal(0.0, 0.2))) if teacher.hesitation > 0 else 0.0
    idle_s = float(rng.uniform(0.1, 0.4))
    end = c0.copy()
    end[:2] += direction * amp
    back = end + (home - end) * teacher.retreat * 0.8
    back[2] = max(back[2], end[2] + 0.02)
    frames: list[tuple[np.ndarray, float, float]] = [(home, idle_s, float(HOME_POSTURE[4]))]
    frames += [(p, reach_s / len(pre), yaw) for p in pre]
    frames.append((c0, descend_s, yaw))
    if pause_s > 0:
        frames.append((c0 + np.array([0.0, 0.0, 0.002]), pause_s, yaw))
    contact_index = len(frames)
    if scene.action == "show me":  # the pointing gesture: a small dip towards the object, then hold
        frames.append((c0 + np.array([0.002, 0.008, -0.01]), act_s * 0.6, yaw))
        contact_index = -1
    else:
        frames.append((end, act_s, yaw))
    frames.append((frames[-1][0], hold_s, yaw))
    frames.append((back, back_s, teacher.wrist_yaw))
    return frames, contact_index


def generate_motion(scene: Scene, teacher: Teacher, rng: np.random.Generator) -> Motion:
    """The arm motion of one recording of `scene` taught by `teacher` (3-6 s at 20 fps).

    The hand path is a chain of minimum-jerk segments between keyframes placed relative to the
    object, plus tremor; each frame is solved by inverse kinematics from the previous frame's
    solution (smooth joints within `JOINT_LIMITS`). The object moves with the hand while in
    contact, only along the action's direction (it is pushed, pulled, slid; never lifted).
    """
    obj0 = OBJECT_HOME + np.asarray(teacher.placement) + rng.normal(0.0, [0.003, 0.006])
    yaw0 = float(rng.normal(0.0, 0.25))
    home = forward_kinematics(HOME_POSTURE)["hand"]
    frames, contact_index, direction = _keyframes(scene, teacher, rng, obj0, home)

    durations = np.array([d for _, d, _ in frames[1:]])
    total = float(np.clip(durations.sum() + frames[0][1], MIN_DURATION_S, MAX_DURATION_S))
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
    contact = segment == contact_index - 1
    hand = hand + _tremor(n, teacher, rng) * np.clip(t / 0.5, 0.0, 1.0)[:, None]
    hand[:, 2] = np.maximum(hand[:, 2], TABLE_Z + 0.006)
    hand = _within_reach(hand)

    joints = np.empty((n, 5))
    q = HOME_POSTURE.copy()
    for i in range(n):
        q = inverse_kinematics(hand[i], q0=q, wrist_yaw=float(wrist[i]))
        joints[i] = q
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
