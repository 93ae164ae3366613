"""Robustness of the shipped model to recordings unlike the corpus (issue 3: "build for variation").

The app will be judged on recordings made elsewhere: other simulators and robots, other camera
poses, lighting, tables and teachers. This benchmark makes out-of-distribution recordings with a
seed other than the corpus's and under named shifts *beyond* the corpus's sampling ranges, each
applied alone, and runs them through exactly the upload path: written in format v1 (.zip), read
back by `data.recording.read_recording`, encoded (`encode_joints`, `encode_frames_found`: the
functions `server.state.Backend.encode_recording` calls) and described by the shipped model.

Shifts (each recording's variant in parentheses; the variants of a shift are spread evenly over
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
shifts compare paired. The scenes are taken in an order where every 16 consecutive ones hold
each action, colour and shape four times; the default 32 recordings per shift cover 32 scenes.

Reported per shift: sentence exact (all, and split into scenes the model was trained on and
held-out scenes), how many recordings lose / gain an exact description against their
in-distribution twin, phoneme F1, slot accuracies, the fraction of frames where vision found no
object, and seconds. The vision-only probe (logistic regressions on the recording-averaged 19
paper features, fitted on the shipped corpus) reads colour and shape, and a proprioception
probe (joints resampled to 24 steps) reads the action: where the probe still reads a slot the
model gets wrong, the model, not the encoder, fails to generalise. Every description that differs
from its twin's is listed after the tables. Results: docs/experiments/robustness.md.

    .venv/bin/python benchmarks/robustness.py [--per-shift 32] [--model data/artefacts/models/default]
        [--seed 1] [--workers 2] [--shifts camera_pose,lighting] [--json out.json] [--sheet out.png]

Default run (256 recordings): 5.2 CPU-minutes, i.e. about 3-4 minutes on two free cores (12.4 min
measured on the shared machine at load average 8-11).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import hashlib
import io
import json
import logging
import math
import sys
import tempfile
import time
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

import cv2
import numpy as np

from data.camera import Appearance, head_angles, project, render_frames
from data.corpus import load_corpus
from data.motion import Motion, Teacher, generate_motion
from data.nao import JOINT_LIMITS
from data.recording import CSV_HEADER, Recording, add_zip_member, read_recording, write_zip
from data.scenario import ACTIONS, COLOURS, SHAPES, Scene, all_scenes
from data.world import FPS, OBJECT_HOME, TABLE_Z
from model.encoding.proprioception import encode_joints
from model.encoding.vision import VISUAL_FEATURES, encode_frames_found, pipeline_steps

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
DEFAULT_MODEL = Path(__file__).resolve().parents[1] / "data" / "artefacts" / "models" / "default"
PROBE_STEPS = 24  # proprioception is resampled to this many steps for the action probe
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


def _retime(motion: Motion, scale: float) -> Motion:
    """The motion played `scale` times slower (> 1) or faster, resampled at its own frame rate."""
    n = len(motion.joints)
    steps = max(2, int(round(n * scale)))
    src = np.minimum(np.arange(steps) / scale, n - 1)
    idx = np.arange(n)

    def warp(values: np.ndarray) -> np.ndarray:
        flat = values.reshape(n, -1)
        out = np.stack([np.interp(src, idx, flat[:, j]) for j in range(flat.shape[1])], axis=1)
        return out.reshape((steps, *values.shape[1:]))

    return Motion(
        joints=warp(motion.joints),
        hand=warp(motion.hand),
        path=warp(motion.path),
        object_xy=warp(motion.object_xy),
        object_yaw=warp(motion.object_yaw),
        contact=motion.contact[np.round(src).astype(int)],
        fps=motion.fps,
    )


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
        motion = _retime(motion, plan.time_scale)
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


def _init_worker() -> None:
    cv2.setNumThreads(1)  # one process per core


def _run_one(task: tuple[Plan, bool]) -> dict:
    """Worker: render, write, read back, encode one plan; optionally keep an annotated frame."""
    plan, keep_frame = task
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="robustness-") as tmp:
        path = write_recording(plan, Path(tmp) / f"{plan.name}.zip")
        t1 = time.perf_counter()
        rec = read_recording(path, path.name)
    t2 = time.perf_counter()
    vision, found = encode_frames_found(rec.frames, workers=1)
    prop = encode_joints(rec.joints, JOINT_LIMITS)
    t3 = time.perf_counter()
    out = {
        "prop": prop,
        "vision": vision,
        "found": found,
        "steps": rec.steps,
        "size": f"{rec.frames.shape[2]}x{rec.frames.shape[1]}",
        "render_s": t1 - t0,
        "read_s": t2 - t1,
        "encode_s": t3 - t2,
        "frame": None,
    }
    if keep_frame:
        out["frame"] = pipeline_steps(rec.frames[rec.steps // 3]).contour
    return out


# ------------------------------------------------------------------------------------------- scoring


@dataclass
class Probes:
    """Linear probes fitted on the shipped corpus: vision -> colour, shape; proprioception -> action."""

    colour: object
    shape: object
    action: object

    @staticmethod
    def vision_features(vision: np.ndarray) -> np.ndarray:
        return vision[:, :VISUAL_FEATURES].mean(axis=0)

    @staticmethod
    def proprio_features(prop: np.ndarray) -> np.ndarray:
        src = np.linspace(0.0, 1.0, len(prop))
        dst = np.linspace(0.0, 1.0, PROBE_STEPS)
        return np.stack([np.interp(dst, src, prop[:, j]) for j in range(prop.shape[1])], axis=1).ravel()

    @classmethod
    def fit(cls, corpus_path: Path | None = None) -> Probes:
        from sklearn.linear_model import LogisticRegression  # imported here: 2 s the test does not need
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        corpus = load_corpus(corpus_path)
        xv = np.stack([cls.vision_features(e.vision) for e in corpus.entries])
        xp = np.stack([cls.proprio_features(e.proprioception) for e in corpus.entries])

        def probe(x: np.ndarray, y: list[str]) -> object:
            return make_pipeline(StandardScaler(), LogisticRegression(C=1.0, max_iter=5000)).fit(x, y)

        return cls(
            colour=probe(xv, [e.scene.colour for e in corpus.entries]),
            shape=probe(xv, [e.scene.shape for e in corpus.entries]),
            action=probe(xp, [e.scene.action for e in corpus.entries]),
        )

    def predict(self, prop: np.ndarray, vision: np.ndarray) -> dict[str, str]:
        xv = self.vision_features(vision)[None]
        xp = self.proprio_features(prop)[None]
        return {
            "colour": str(self.colour.predict(xv)[0]),
            "shape": str(self.shape.predict(xv)[0]),
            "action": str(self.action.predict(xp)[0]),
        }


def model_info(model_dir: Path) -> dict:
    """What makes the numbers traceable: the checkpoint's hash, date and its own metrics."""
    meta = json.loads((model_dir / "meta.json").read_text())
    weights = (model_dir / "model.safetensors").read_bytes()
    test = meta.get("metrics", {}).get("test", {})
    return {
        "path": str(model_dir),
        "sha256": hashlib.sha256(weights).hexdigest()[:16],
        "created": meta.get("created"),
        "modified": time.strftime(
            "%Y-%m-%d %H:%M UTC", time.gmtime((model_dir / "model.safetensors").stat().st_mtime)
        ),
        "mode": meta.get("mode"),
        "test_sentence_exact": test.get("sentence_exact"),
        "test_f1": test.get("f1"),
        "train_ids": meta.get("split", {}).get("train", []),
    }


def describe_all(model_dir: Path, results: list[dict]) -> list[dict]:
    """Describe every recording with the model and score it against its scene's utterance."""
    import torch

    from model import checkpoint
    from model.encoding.utterance import Lexicon, text_to_phonemes
    from model.metrics import Transcript, score

    torch.set_num_threads(1)
    model, meta = checkpoint.load(model_dir)
    lexicon = Lexicon(meta["lexicon"])
    t0 = time.perf_counter()
    descriptions = model.describe_batch([r["prop"] for r in results], [r["vision"] for r in results], lexicon)
    per = (time.perf_counter() - t0) / max(len(results), 1)
    scored = []
    for r, d in zip(results, descriptions, strict=True):
        target = r["plan"].scene.utterance
        s = score(
            Transcript(tuple(d.phonemes), d.text),
            Transcript(tuple(text_to_phonemes(target)), target),
            ACTIONS,
            COLOURS,
            SHAPES,
        )
        scored.append({"text": d.text, "describe_s": per, **dataclasses.asdict(s)})
    return scored


def summarise_rows(rows: list[dict], train_scenes: set[str]) -> dict[str, float]:
    """Means over recordings of one shift (or one variant)."""

    def mean(key: str, subset: list[dict] | None = None) -> float:
        subset = rows if subset is None else subset
        return float(np.mean([r[key] for r in subset])) if subset else float("nan")

    seen = [r for r in rows if r["scene"] in train_scenes]
    unseen = [r for r in rows if r["scene"] not in train_scenes]
    paired = [r for r in rows if r["base_exact"] is not None]
    return {
        "n": len(rows),
        "exact": mean("sentence_exact"),
        "exact_seen": mean("sentence_exact", seen),
        "exact_unseen": mean("sentence_exact", unseen),
        "f1": mean("f1"),
        "action": mean("slot_action"),
        "colour": mean("slot_colour"),
        "object": mean("slot_object"),
        "no_object": mean("no_object"),
        "probe_colour": mean("probe_colour"),
        "probe_shape": mean("probe_shape"),
        "probe_action": mean("probe_action"),
        "seconds": float(sum(r["render_s"] + r["read_s"] + r["encode_s"] + r["describe_s"] for r in rows)),
        "upload_s": mean("upload_s"),
        # paired with the in-distribution recording of the same scene and base draws
        "lost": float(sum(r["base_exact"] == 1.0 and r["sentence_exact"] == 0.0 for r in paired))
        if paired
        else float("nan"),
        "gained": float(sum(r["base_exact"] == 0.0 and r["sentence_exact"] == 1.0 for r in paired))
        if paired
        else float("nan"),
    }


COLUMNS = (
    ("n", "n", "{:.0f}"),
    ("exact", "exact", "{:.3f}"),
    ("exact_seen", "seen", "{:.3f}"),
    ("exact_unseen", "unseen", "{:.3f}"),
    ("lost", "lost", "{:.0f}"),
    ("gained", "gain", "{:.0f}"),
    ("f1", "F1", "{:.3f}"),
    ("action", "action", "{:.3f}"),
    ("colour", "colour", "{:.3f}"),
    ("object", "object", "{:.3f}"),
    ("no_object", "no-obj", "{:.3f}"),
    ("probe_colour", "p.col", "{:.3f}"),
    ("probe_shape", "p.shp", "{:.3f}"),
    ("probe_action", "p.act", "{:.3f}"),
    ("seconds", "s", "{:.0f}"),
    ("upload_s", "s/upl", "{:.2f}"),
)


def format_table(rows: dict[str, dict[str, float]], label: str) -> str:
    """A markdown table, one row per key of `rows`."""
    head = f"| {label} | " + " | ".join(title for _, title, _ in COLUMNS) + " |"
    rule = "|---" * (len(COLUMNS) + 1) + "|"
    lines = [head, rule]
    for name, values in rows.items():
        cells = [fmt.format(values[key]) if not math.isnan(values[key]) else "-" for key, _, fmt in COLUMNS]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def changed_descriptions(records: list[dict]) -> list[str]:
    """Every shifted recording the model describes differently from its in-distribution twin."""
    base = {r["number"]: r for r in records if r["shift"] == "in_distribution"}
    lines = []
    for r in records:
        twin = base.get(r["number"])
        if r["shift"] == "in_distribution" or twin is None or twin["text"] == r["text"]:
            continue
        probes = "".join(k[0] if r[f"probe_{k}"] else "-" for k in ("action", "colour", "shape"))
        lines.append(
            f"{r['shift']} / {r['variant']}: {r['target']!r} in-distribution {twin['text']!r} -> "
            f"{r['text']!r} (probes right: {probes})"
        )
    return lines


def contact_sheet(rows: list[tuple[str, list[tuple[str, np.ndarray]]]], path: Path) -> Path:
    """One row of labelled frames (vision contour drawn) per shift; RGB in, PNG out."""
    cell_w, cell_h, label_h, name_w = 240, 180, 16, 104
    columns = max(len(cells) for _, cells in rows)
    sheet = np.full((len(rows) * (cell_h + label_h), name_w + columns * cell_w, 3), 255, np.uint8)
    font = cv2.FONT_HERSHEY_SIMPLEX
    for r, (name, cells) in enumerate(rows):
        y = r * (cell_h + label_h)
        cv2.putText(sheet, name, (4, y + label_h + cell_h // 2), font, 0.42, (0, 0, 0), 1, cv2.LINE_AA)
        for c, (label, frame) in enumerate(cells):
            x = name_w + c * cell_w
            shrink = frame.shape[1] > cell_w
            sheet[y + label_h : y + label_h + cell_h, x : x + cell_w] = cv2.resize(
                frame, (cell_w, cell_h), interpolation=cv2.INTER_AREA if shrink else cv2.INTER_NEAREST
            )
            cv2.putText(sheet, label, (x + 3, y + 12), font, 0.36, (0, 0, 0), 1, cv2.LINE_AA)
    path.parent.mkdir(parents=True, exist_ok=True)
    quality = [cv2.IMWRITE_JPEG_QUALITY, 88] if path.suffix.lower() in (".jpg", ".jpeg") else []
    cv2.imwrite(str(path), cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR), quality)
    return path


def _sheet_picks(plans: list[Plan], shifts: Sequence[str], per_row: int = 4) -> dict[str, list[int]]:
    """Per shift, up to `per_row` recordings: the first of each variant, then the second, ..."""
    picks = {}
    for shift in shifts:
        lists = [
            [i for i, p in enumerate(plans) if p.shift == shift and p.variant == v] for v in VARIANTS[shift]
        ]
        rounds = max(len(lst) for lst in lists)
        picks[shift] = [lst[j] for j in range(rounds) for lst in lists if j < len(lst)][:per_row]
    return picks


# ---------------------------------------------------------------------------------------------- main


def run(
    shifts: Sequence[str], per_shift: int, seed: int, model_dir: Path, workers: int, sheet: Path | None
) -> dict:
    order = scene_order()
    plans: list[Plan] = []
    for shift in shifts:
        variants = assign_variants(shift, per_shift, seed)
        plans += [make_plan(shift, order[k % len(order)], k, seed, variants[k]) for k in range(per_shift)]
    picks = _sheet_picks(plans, shifts) if sheet is not None else {}
    keep = {i for chosen in picks.values() for i in chosen}
    tasks = [(p, i in keep) for i, p in enumerate(plans)]

    from tqdm import tqdm

    start = time.perf_counter()
    if workers <= 1:
        _init_worker()
        outputs = [_run_one(t) for t in tqdm(tasks, desc="recordings")]
    else:
        with get_context("spawn").Pool(workers, initializer=_init_worker) as pool:
            outputs = list(tqdm(pool.imap(_run_one, tasks, chunksize=1), total=len(tasks), desc="recordings"))
    for plan, out in zip(plans, outputs, strict=True):
        out["plan"] = plan
    scored = describe_all(model_dir, outputs)
    probes = Probes.fit()
    info = model_info(model_dir)
    train_scenes = {rid.rsplit("-", 1)[0] for rid in info.pop("train_ids")}

    records = []
    for out, s in zip(outputs, scored, strict=True):
        plan: Plan = out["plan"]
        guess = probes.predict(out["prop"], out["vision"])
        records.append(
            {
                "shift": plan.shift,
                "variant": plan.variant,
                "scene": plan.scene.id,
                "number": plan.number,
                "target": plan.scene.utterance,
                "steps": out["steps"],
                "size": out["size"],
                "no_object": float(1.0 - out["found"].mean()),
                "probe_colour": float(guess["colour"] == plan.scene.colour),
                "probe_shape": float(guess["shape"] == plan.scene.shape),
                "probe_action": float(guess["action"] == plan.scene.action),
                "render_s": out["render_s"],
                "read_s": out["read_s"],
                "encode_s": out["encode_s"],
                "upload_s": out["read_s"] + out["encode_s"] + s["describe_s"],
                **s,
            }
        )
    base = {r["number"]: r["sentence_exact"] for r in records if r["shift"] == "in_distribution"}
    for r in records:  # recording k of every shift shares scene and base draws with in_distribution's k
        r["base_exact"] = base.get(r["number"]) if r["shift"] != "in_distribution" else None
    by_shift = {sh: summarise_rows([r for r in records if r["shift"] == sh], train_scenes) for sh in shifts}
    by_variant = {
        f"{sh} / {v}": summarise_rows(
            [r for r in records if r["shift"] == sh and r["variant"] == v], train_scenes
        )
        for sh in shifts
        for v in VARIANTS[sh]
        if any(r["shift"] == sh and r["variant"] == v for r in records)
    }
    if sheet is not None:
        rows = []
        for shift, chosen in picks.items():
            cells = []
            for i in chosen:
                r = records[i]
                label = f"{r['variant']} {r['size']}, found {1.0 - r['no_object']:.0%}"
                cells.append((label, outputs[i]["frame"]))
            rows.append((shift, cells))
        contact_sheet(rows, sheet)
    return {
        "model": info,
        "seed": seed,
        "per_shift": per_shift,
        "wall_seconds": time.perf_counter() - start,
        "shifts": by_shift,
        "variants": by_variant,
        "recordings": records,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--per-shift", type=int, default=32, help="recordings per shift (spread over the scenes)"
    )
    parser.add_argument("--model", type=Path, default=DEFAULT_MODEL, help="model checkpoint folder")
    parser.add_argument("--seed", type=int, default=1, help="base seed (must differ from the corpus's)")
    parser.add_argument("--workers", type=int, default=2, help="processes rendering and encoding")
    parser.add_argument(
        "--shifts", default=",".join(SHIFTS), help="comma-separated subset of " + ", ".join(SHIFTS)
    )
    parser.add_argument(
        "--json", type=Path, default=None, help="write every number (and each recording) here"
    )
    parser.add_argument(
        "--sheet", type=Path, default=None, help="write a contact sheet PNG, one frame per variant"
    )
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    shifts = [s.strip() for s in args.shifts.split(",") if s.strip()]
    unknown = [s for s in shifts if s not in SHIFTS]
    if unknown:
        parser.error(f"unknown shifts {unknown}; expected some of {SHIFTS}")
    corpus_seed = load_corpus().seed
    if args.seed == corpus_seed:
        parser.error(f"--seed {args.seed} is the shipped corpus's seed; out-of-distribution needs another")
    if args.per_shift < 1:
        parser.error("--per-shift must be at least 1")

    result = run(shifts, args.per_shift, args.seed, args.model, args.workers, args.sheet)
    info = result["model"]
    print(
        f"model {info['path']} (sha256 {info['sha256']}, modified {info['modified']}, "
        f"created {info['created']}, "
        f"mode {info['mode']}; its own test split: exact {info['test_sentence_exact']}, F1 {info['test_f1']})"
    )
    print(f"seed {args.seed}, {args.per_shift} recordings per shift, wall {result['wall_seconds']:.0f} s")
    print("seen/unseen: exact on scenes the model was / was not trained on; p.*: linear probes fitted")
    print("on the shipped corpus (vision means -> colour, shape; proprioception -> action);")
    print("lost/gain: recordings described exactly in in_distribution but not under the shift / vice versa")
    print("(same scene, teacher, motion and look but for the shift); s: worker + model seconds;")
    print("s/upl: read_recording + encode + describe per recording")
    print(format_table(result["shifts"], "shift"))
    print()
    print(format_table(result["variants"], "shift / variant"))
    changed = changed_descriptions(result["recordings"])
    if changed:
        print("\ndescriptions unlike the in-distribution twin's (probes right: a=action c=colour s=shape):")
        print("\n".join(changed))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
