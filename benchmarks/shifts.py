"""The robustness benchmark's recordings: named shifts beyond the corpus's sampling ranges, the plan
each shifted recording is made from, and the recording itself, written in format v1 and read back.


The shifts (each recording's variant in parentheses; the variants of a shift are spread evenly over
its recordings):

- ``in_distribution``: a fresh seed, the corpus's own sampling.
- ``camera_pose``: (fov) horizontal field of view 40-46 or 76-84 deg (corpus 52-70); (displaced)
  camera moved 3.5-5 cm sideways and 5-8 cm up or 3-4.5 cm down (corpus: within 2 cm sideways,
  -1.5..+3 cm vertically), re-aimed at the workspace; (off-centre) head turned so that the
  object starts 15-28 % of the width from the left or right edge, 18-34 % of the height from the
  top or 14-20 % from the bottom (corpus: 36-62 % across, 44-71 % down); (rolled) 0.22-0.35 rad
  camera roll (corpus sd 0.04).
- ``lighting``: (dark) exposure 0.3-0.45 and dim ambient light; (bright) exposure 1.5-1.9,
  clipping; (warm cast) tungsten-like white balance, blue gain 0.55-0.7; (cool cast) red gain
  0.6-0.72, blue 1.3-1.45 (corpus: exposure 0.75-1.2, every gain 0.86-1.14).
- ``table``: (dark) near-black table; (saturated plain), (saturated cloth) saturation 0.45-0.75
  of any hue (corpus <= 0.45); (red wood) a saturated reddish wood, hue 0-15 deg.
- ``teacher``: (slow) tempo 0.4-0.55 and the motion played 1.4-1.7x slower (longer than any
  corpus recording); (fast) tempo 1.7-2.1 played 0.55-0.7x (shorter than any); (large) amplitude
  and approach height 7-9 cm, approach angle 0.6-0.8 rad; (hesitant) a 1-1.6 s pause, 4-7 mm
  tremor, a 1.5-2.5 cm push. `generate_motion` fits every motion into 3-6 s, so the speed
  variants re-time its result.
- ``resolution``: frames rendered at (640x480) or (160x120) instead of 320x240.
- ``noise_blur``: (noise) sensor noise sd 12-20 grey levels (corpus 1-7); (blur) Gaussian blur
  sd 2-3 px (corpus <= 1.3); (noise+blur) both.
- ``fps``: joints.csv at 50 Hz and frames at 10 fps, with meta.json giving the frame rate
  (meta fps) or not (spread: frames spread evenly over the joint time span), so that reading
  resamples both onto the 20 Hz grid.

Recording k of every shift shows the same scene with the same base teacher, motion stream and
appearance (drawn from ``(seed, scene, k)``); only the shift's own parameters differ, so the
shifts compare paired (`make_plan`). `scene_order` takes the scenes so that every 16 consecutive
ones hold each action, colour and shape four times.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from data.camera import Appearance, head_angles, project, render_frames
from data.motion import Motion, Teacher, generate_motion, retimed
from data.recording import CSV_HEADER, Recording, add_zip_member, read_recording, write_zip
from data.scenario import ACTIONS, COLOURS, SHAPES, Scene, all_scenes
from data.world import FPS, OBJECT_HOME, TABLE_Z

SHIFTS: tuple[str, ...] = (
    "in_distribution",
    "camera_pose",
    "lighting",
    "table",
    "teacher",
    "resolution",
    "noise_blur",
    "fps",
)
VARIANTS: dict[str, tuple[str, ...]] = {
    "in_distribution": ("fresh seed",),
    "camera_pose": ("fov", "displaced", "off-centre", "rolled"),
    "lighting": ("dark", "bright", "warm cast", "cool cast"),
    "table": ("dark", "saturated plain", "saturated cloth", "red wood"),
    "teacher": ("slow", "fast", "large", "hesitant"),
    "resolution": ("640x480", "160x120"),
    "noise_blur": ("noise", "blur", "noise+blur"),
    "fps": ("meta fps", "spread"),
}
SHIFTED_JOINT_RATE = 50.0  # Hz, the fps shift's joints.csv
SHIFTED_FRAME_RATE = 10.0  # Hz, the fps shift's frames


# -------------------------------------------------------------------------------------- the shifts


@dataclass(frozen=True)
class Plan:
    """Everything one shifted recording is made from (deterministic; cheap to pickle to a worker)."""

    shift: str
    variant: str
    scene: Scene
    number: int  # recording number within the shift: base draws come from (seed, scene, number)
    seed: int
    teacher: Teacher
    appearance: Appearance
    time_scale: float = 1.0  # > 1: the motion is played this many times slower
    joint_rate: float = FPS  # Hz of joints.csv
    frame_rate: float = FPS  # Hz of the frames
    meta_fps: bool = True  # meta.json states the frame rate (else frames spread over the joints' span)

    @property
    def name(self) -> str:
        return f"{self.shift}-{self.scene.id}-{self.number}"


def scene_order() -> list[Scene]:
    """The 64 scenes ordered so that every block of 16 holds each action, colour and shape 4 times
    (shape = action + colour + offset mod 4, offsets 0, 2, 1, 3): any 16k-prefix is balanced."""
    rank = {0: 0, 2: 1, 1: 2, 3: 3}

    def key(s: Scene) -> tuple[int, int]:
        offset = (SHAPES.index(s.shape) - ACTIONS.index(s.action) - COLOURS.index(s.colour)) % 4
        return rank[offset], s.index

    return sorted(all_scenes(), key=key)


def assign_variants(shift: str, count: int, seed: int) -> list[str]:
    """The variant of each of `count` recordings: equally often each, in a seeded random order."""
    names = VARIANTS[shift]
    order = np.resize(np.arange(len(names)), count)
    order = np.random.default_rng([seed, SHIFTS.index(shift)]).permutation(order)
    return [names[i] for i in order]


def _streams(seed: int, scene: Scene, number: int) -> list[np.random.SeedSequence]:
    """Teacher, motion, appearance and shift streams of one recording (the same for every shift)."""
    return np.random.SeedSequence([seed, scene.index, number]).spawn(4)


def _sign(rng: np.random.Generator) -> float:
    return 1.0 if rng.random() < 0.5 else -1.0


def _corpus_aim(rng: np.random.Generator) -> np.ndarray:
    """An aim point as `Appearance.sample` draws it (near the workspace in front of the arm)."""
    return np.array([0.13 + rng.uniform(-0.02, 0.02), -0.105 + rng.uniform(-0.025, 0.025), TABLE_Z])


def _object_at(app: Appearance, target: np.ndarray) -> Appearance:
    """The appearance with head yaw and pitch turned (Newton steps, pitch not limited: another robot)
    so that the object's home position appears at `target` (fractions of width and height)."""
    home = np.append(OBJECT_HOME, TABLE_Z)[None]
    size = np.array([app.width, app.height], dtype=float)

    def where(yaw: float, pitch: float) -> np.ndarray:
        return project(dataclasses.replace(app, head_yaw=yaw, head_pitch=pitch), home)[0] / size

    angles = np.array([app.head_yaw, app.head_pitch])
    for _ in range(6):
        here = where(*angles)
        eps = 1e-4
        jacobian = np.column_stack([(where(*(angles + d)) - here) / eps for d in np.eye(2) * eps])
        angles = angles + np.linalg.solve(jacobian, target - here)
    return dataclasses.replace(app, head_yaw=float(angles[0]), head_pitch=float(angles[1]))


def _camera_pose(app: Appearance, variant: str, rng: np.random.Generator) -> Appearance:
    if variant == "fov":
        hfov = rng.uniform(40.0, 46.0) if rng.random() < 0.5 else rng.uniform(76.0, 84.0)
        return dataclasses.replace(app, hfov=float(np.deg2rad(hfov)))
    if variant == "displaced":  # another robot: the camera to the side and higher or lower
        up = rng.uniform(0.05, 0.08) if rng.random() < 0.5 else -rng.uniform(0.03, 0.045)
        offset = (float(rng.uniform(-0.02, 0.02)), _sign(rng) * float(rng.uniform(0.035, 0.05)), float(up))
        yaw, pitch = head_angles(_corpus_aim(rng), offset)
        return dataclasses.replace(app, camera_offset=offset, head_yaw=yaw, head_pitch=pitch)
    if variant == "off-centre":  # the head looks past the object: it appears where the corpus never has it
        side = int(rng.integers(4))
        if side < 2:  # left or right
            u = rng.uniform(0.15, 0.28) if side == 0 else rng.uniform(0.72, 0.85)
            target = (u, rng.uniform(0.3, 0.8))
        else:  # top or bottom
            v = rng.uniform(0.18, 0.34) if side == 2 else rng.uniform(0.8, 0.86)
            target = (rng.uniform(0.25, 0.75), v)
        return _object_at(app, np.array(target))
    if variant == "rolled":
        return dataclasses.replace(app, camera_roll=_sign(rng) * float(rng.uniform(0.22, 0.35)))
    raise ValueError(f"unknown camera_pose variant {variant!r}")


def _lighting(app: Appearance, variant: str, rng: np.random.Generator) -> Appearance:
    if variant == "dark":
        return dataclasses.replace(
            app, exposure=float(rng.uniform(0.3, 0.45)), ambient=float(rng.uniform(0.12, 0.22))
        )
    if variant == "bright":
        return dataclasses.replace(app, exposure=float(rng.uniform(1.5, 1.9)))
    if variant == "warm cast":  # tungsten light on a daylight white balance
        gains = (rng.uniform(1.3, 1.45), rng.uniform(0.95, 1.05), rng.uniform(0.55, 0.7))
    elif variant == "cool cast":  # shade / daylight on a tungsten white balance
        gains = (rng.uniform(0.6, 0.72), rng.uniform(0.95, 1.05), rng.uniform(1.3, 1.45))
    else:
        raise ValueError(f"unknown lighting variant {variant!r}")
    return dataclasses.replace(app, white_balance=tuple(float(g) for g in gains))


def _table(app: Appearance, variant: str, rng: np.random.Generator) -> Appearance:
    if variant == "dark":
        kind, hsv = "plain", (rng.uniform(0.0, 360.0), rng.uniform(0.0, 0.15), rng.uniform(0.05, 0.16))
    elif variant == "saturated plain":
        kind, hsv = "plain", (rng.uniform(0.0, 360.0), rng.uniform(0.45, 0.7), rng.uniform(0.4, 0.8))
    elif variant == "saturated cloth":
        kind, hsv = "cloth", (rng.uniform(0.0, 360.0), rng.uniform(0.5, 0.75), rng.uniform(0.35, 0.8))
    elif variant == "red wood":  # mahogany / cherry: close to the red objects' hue
        kind, hsv = "wood", (rng.uniform(0.0, 15.0), rng.uniform(0.55, 0.75), rng.uniform(0.3, 0.55))
    else:
        raise ValueError(f"unknown table variant {variant!r}")
    return dataclasses.replace(app, table_kind=kind, table_hsv=tuple(float(v) for v in hsv))


def _teacher(teacher: Teacher, variant: str, rng: np.random.Generator) -> tuple[Teacher, float]:
    """The shifted teacher and the time scale its motion is played at."""
    if variant == "slow":
        return dataclasses.replace(teacher, tempo=float(rng.uniform(0.4, 0.55))), float(rng.uniform(1.4, 1.7))
    if variant == "fast":
        return dataclasses.replace(teacher, tempo=float(rng.uniform(1.7, 2.1))), float(rng.uniform(0.55, 0.7))
    if variant == "large":
        shifted = dataclasses.replace(
            teacher,
            amplitude=float(rng.uniform(0.07, 0.09)),
            approach_height=float(rng.uniform(0.07, 0.09)),
            approach_angle=_sign(rng) * float(rng.uniform(0.6, 0.8)),
        )
        return shifted, 1.0
    if variant == "hesitant":
        shifted = dataclasses.replace(
            teacher,
            hesitation=float(rng.uniform(1.0, 1.6)),
            tremor=float(rng.uniform(0.004, 0.007)),
            amplitude=float(rng.uniform(0.015, 0.025)),
        )
        return shifted, 1.0
    raise ValueError(f"unknown teacher variant {variant!r}")


def _noise_blur(app: Appearance, variant: str, rng: np.random.Generator) -> Appearance:
    noise = float(rng.uniform(12.0, 20.0)) if variant in ("noise", "noise+blur") else app.noise_sigma
    blur = float(rng.uniform(2.0, 3.0)) if variant in ("blur", "noise+blur") else app.blur_sigma
    if variant not in ("noise", "blur", "noise+blur"):
        raise ValueError(f"unknown noise_blur variant {variant!r}")
    return dataclasses.replace(app, noise_sigma=noise, blur_sigma=blur)


def make_plan(shift: str, scene: Scene, number: int, seed: int, variant: str | None = None) -> Plan:
    """Recording `number` of `shift` for `scene`: the base draws of (seed, scene, number), then the
    shift's own parameters (variant: one of `VARIANTS[shift]`, the first by default)."""
    if shift not in SHIFTS:
        raise ValueError(f"unknown shift {shift!r}; expected one of {SHIFTS}")
    variant = variant or VARIANTS[shift][0]
    if variant not in VARIANTS[shift]:
        raise ValueError(f"unknown {shift} variant {variant!r}; expected one of {VARIANTS[shift]}")
    teacher_seq, _, appearance_seq, shift_seq = _streams(seed, scene, number)
    teacher = Teacher.sample(np.random.default_rng(teacher_seq))
    app = Appearance.sample(np.random.default_rng(appearance_seq))
    rng = np.random.default_rng(shift_seq)
    plan = Plan(shift, variant, scene, number, seed, teacher, app)
    if shift == "camera_pose":
        plan = dataclasses.replace(plan, appearance=_camera_pose(app, variant, rng))
    elif shift == "lighting":
        plan = dataclasses.replace(plan, appearance=_lighting(app, variant, rng))
    elif shift == "table":
        plan = dataclasses.replace(plan, appearance=_table(app, variant, rng))
    elif shift == "teacher":
        shifted, scale = _teacher(teacher, variant, rng)
        plan = dataclasses.replace(plan, teacher=shifted, time_scale=scale)
    elif shift == "resolution":
        width, height = (int(v) for v in variant.split("x"))
        plan = dataclasses.replace(plan, appearance=dataclasses.replace(app, width=width, height=height))
    elif shift == "noise_blur":
        plan = dataclasses.replace(plan, appearance=_noise_blur(app, variant, rng))
    elif shift == "fps":
        plan = dataclasses.replace(
            plan,
            joint_rate=SHIFTED_JOINT_RATE,
            frame_rate=SHIFTED_FRAME_RATE,
            meta_fps=variant == "meta fps",
        )
    return plan


# ------------------------------------------------------------------------------ making the recording


def _every(motion: Motion, stride: int) -> Motion:
    """Every `stride`-th time step of the motion (a camera at a lower frame rate)."""
    return Motion(
        joints=motion.joints[::stride],
        hand=motion.hand[::stride],
        path=motion.path[::stride],
        object_xy=motion.object_xy[::stride],
        object_yaw=motion.object_yaw[::stride],
        contact=motion.contact[::stride],
        fps=int(round(motion.fps / stride)),
    )


def simulate(plan: Plan, steps: int | None = None) -> Motion:
    """The plan's motion at 20 Hz (re-timed for the speed variants), cut to `steps` if given."""
    motion_seq = _streams(plan.seed, plan.scene, plan.number)[1]
    motion = generate_motion(plan.scene, plan.teacher, np.random.default_rng(motion_seq))
    if plan.time_scale != 1.0:
        motion = retimed(motion, plan.time_scale)
    if steps is not None:
        motion = dataclasses.replace(
            motion,
            **{
                f: getattr(motion, f)[:steps]
                for f in ("joints", "hand", "path", "object_xy", "object_yaw", "contact")
            },
        )
    return motion


def _write_rates(plan: Plan, motion: Motion, path: Path) -> Path:
    """A format-v1 .zip with joints.csv at `plan.joint_rate` and frames at `plan.frame_rate`."""
    stride = int(round(motion.fps / plan.frame_rate))
    frames = render_frames(plan.scene, _every(motion, stride), plan.appearance)
    span = (len(motion.joints) - 1) / motion.fps
    times = np.arange(int(math.floor(span * plan.joint_rate + 1e-9)) + 1) / plan.joint_rate
    src = np.arange(len(motion.joints)) / motion.fps
    joints = np.stack([np.interp(times, src, motion.joints[:, j]) for j in range(motion.joints.shape[1])], 1)
    table = io.StringIO()
    writer = csv.writer(table, lineterminator="\n")
    writer.writerow(CSV_HEADER)
    for t, row in zip(times, joints, strict=True):
        writer.writerow([repr(float(t)), *(repr(float(v)) for v in row)])
    meta: dict[str, object] = {"format": 1, "utterance": plan.scene.utterance}
    if plan.meta_fps:
        meta["fps"] = plan.frame_rate
    with zipfile.ZipFile(path, "w") as archive:
        add_zip_member(archive, "joints.csv", table.getvalue().encode(), zipfile.ZIP_DEFLATED)
        add_zip_member(archive, "meta.json", json.dumps(meta).encode(), zipfile.ZIP_DEFLATED)
        for i, frame in enumerate(frames):
            ok, png = cv2.imencode(".png", cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
            if not ok:
                raise RuntimeError(f"frame {i} of {plan.name} could not be encoded as PNG")
            add_zip_member(archive, f"frames/{i:05d}.png", png.tobytes(), zipfile.ZIP_STORED)
    return path


def write_recording(plan: Plan, path: Path, steps: int | None = None) -> Path:
    """Render the plan and write it as a format-v1 .zip at `path` (PNG frames)."""
    motion = simulate(plan, steps)
    if plan.joint_rate != FPS or plan.frame_rate != FPS:
        return _write_rates(plan, motion, path)
    frames = render_frames(plan.scene, motion, plan.appearance)
    return write_zip(Recording(motion.joints, frames, fps=FPS, utterance=plan.scene.utterance), path)


def make_recording(plan: Plan, steps: int | None = None) -> Recording:
    """The plan's recording as an upload would arrive: written to a .zip and read back."""
    with tempfile.TemporaryDirectory(prefix="robustness-") as tmp:
        path = write_recording(plan, Path(tmp) / f"{plan.name}.zip", steps)
        return read_recording(path, path.name)
