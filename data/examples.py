"""Recordings to try: what someone without a NAO can download, look at and upload (format v1).

Two kinds, each made deterministically from fixed seeds:

- ``corpus``: one corpus recording of each action, exported as the corpus built with
  `CORPUS_SEED` holds it (`data.corpus.export_recording`: the same frames, re-rendered).
- ``unlike``: a fresh scene whose teacher (`data.motion.Teacher`) and look (`data.camera.Appearance`)
  are drawn as the corpus draws them, then moved outside the ranges the corpus samples on purpose:
  another robot's camera, dim warm light, a slow and a fast teacher (tempo, and the motion played
  slower or faster than `generate_motion`'s 3-6 s allow), a low-resolution camera (frames resized)
  and a 30 fps camera (the motion resampled). Reading resamples them onto the model's 20 Hz grid
  like any upload, so they show what the model makes of data it never saw the like of.

`EXAMPLES` lists them by name; `Example.recording()` renders one (a few seconds); `write_example`
writes it as a format-v1 .zip (`data.recording.write_zip`, atomic).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import cv2
import numpy as np

from data.camera import Appearance, head_angles, render_frames
from data.corpus import export_recording
from data.motion import Teacher, generate_motion, retimed
from data.recording import Recording, write_zip
from data.scenario import Scene, recording_id
from data.world import FPS, TABLE_Z

CORPUS_SEED = 0  # the seed the shipped corpus is built with (`mtrnn corpus build`)
EXAMPLES_SEED = 15  # the fresh draws of the recordings unlike the corpus
VERSION = 1  # bump when a recording below changes, so that cached copies are made again

Kind = Literal["corpus", "unlike"]


@dataclass(frozen=True)
class Example:
    """One recording to try: its name (URL-safe), its scene, what is special about it, how to make it."""

    name: str
    scene: Scene
    title: str
    description: str
    kind: Kind
    make: Callable[[Scene], Recording]

    def recording(self) -> Recording:
        return self.make(self.scene)


# ------------------------------------------------------------------------------ the shifted draws


@dataclass(frozen=True)
class Draw:
    """A scene's teacher, appearance and motion stream, drawn as the corpus draws them."""

    scene: Scene
    teacher: Teacher
    appearance: Appearance
    motion_seed: np.random.SeedSequence  # the trial-to-trial variation of `generate_motion`


def draw_for(scene: Scene) -> Draw:
    """The teacher, appearance and motion stream of `scene` from `EXAMPLES_SEED`."""
    teacher_seq, motion_seq, appearance_seq = np.random.SeedSequence([EXAMPLES_SEED, scene.index]).spawn(3)
    return Draw(
        scene,
        Teacher.sample(np.random.default_rng(teacher_seq)),
        Appearance.sample(np.random.default_rng(appearance_seq)),
        motion_seq,
    )


def render(draw: Draw, slower: float = 1.0, fps: float = FPS) -> Recording:
    """The draw's motion, played `slower` times slower and sampled at `fps`, seen by its camera."""
    motion = generate_motion(draw.scene, draw.teacher, np.random.default_rng(draw.motion_seed))
    if slower != 1.0 or fps != motion.fps:
        motion = retimed(motion, slower, fps)
    frames = render_frames(draw.scene, motion, draw.appearance)
    return Recording(motion.joints, frames, fps=fps, utterance=draw.scene.utterance)


def other_camera(draw: Draw) -> Draw:
    """Another robot's head: the camera 4.5 cm to the left and 7 cm higher (corpus: within 2 cm and
    -1.5..+3 cm), an 80 degree field of view (corpus 52-70), re-aimed at the workspace."""
    offset = (0.0, 0.045, 0.07)
    yaw, pitch = head_angles(np.array([0.13, -0.105, TABLE_Z]), offset)
    app = dataclasses.replace(
        draw.appearance, camera_offset=offset, head_yaw=yaw, head_pitch=pitch, hfov=float(np.deg2rad(80.0))
    )
    return dataclasses.replace(draw, appearance=app)


def dim_warm_light(draw: Draw) -> Draw:
    """Tungsten light on a daylight white balance: exposure 0.4 (corpus 0.75-1.2), ambient 0.18
    (corpus 0.3-0.55), gains R 1.38, B 0.62 (corpus 0.86-1.14 each)."""
    app = dataclasses.replace(draw.appearance, exposure=0.4, ambient=0.18, white_balance=(1.38, 1.0, 0.62))
    return dataclasses.replace(draw, appearance=app)


def teacher_tempo(draw: Draw, tempo: float) -> Draw:
    """The same teacher at another `tempo` (corpus 0.7-1.45)."""
    return dataclasses.replace(draw, teacher=dataclasses.replace(draw.teacher, tempo=tempo))


def low_resolution(rec: Recording, width: int = 160, height: int = 120) -> Recording:
    """The frames resized to `width` x `height` (the corpus is 320 x 240), as a cheap webcam gives."""
    small = np.stack([cv2.resize(f, (width, height), interpolation=cv2.INTER_AREA) for f in rec.frames])
    return Recording(rec.joints, small, fps=rec.fps, utterance=rec.utterance)


# ---------------------------------------------------------------------------------- the catalogue


def _corpus(scene: Scene, variant: int) -> Example:
    rid = recording_id(scene, variant)
    return Example(
        name=f"corpus-{rid}",
        scene=scene,
        title=f"{scene.utterance[:-1]} (corpus recording {rid})",
        description=f"Recording {rid} of the corpus, as `mtrnn corpus export` writes it: "
        "320x240 frames at 20 fps and the teacher's sentence.",
        kind="corpus",
        make=lambda _: export_recording(rid, CORPUS_SEED),
    )


def _unlike(
    name: str, scene: Scene, how: str, description: str, make: Callable[[Draw], Recording]
) -> Example:
    title = f"{scene.utterance[:-1]}, {how}"
    return Example(name, scene, title, description, "unlike", lambda s: make(draw_for(s)))


def _catalogue() -> tuple[Example, ...]:
    return (
        _corpus(Scene("pull", "red", "apple"), 0),
        _corpus(Scene("push", "blue", "dice"), 1),
        _corpus(Scene("show me", "green", "banana"), 2),
        _corpus(Scene("slide", "yellow", "phone"), 3),
        _unlike(
            "other-camera",
            Scene("push", "green", "apple"),
            "seen by another robot's camera",
            "The camera sits 4.5 cm further left and 7 cm higher than the corpus ever has it, "
            "with an 80 degree field of view (corpus 52-70).",
            lambda draw: render(other_camera(draw)),
        ),
        _unlike(
            "dim-warm-light",
            Scene("slide", "blue", "banana"),
            "in dim tungsten light",
            "Exposure 0.4 and dim ambient light (corpus 0.75-1.2, 0.3-0.55), and a warm colour cast: "
            "red gain 1.38, blue 0.62 (corpus 0.86-1.14).",
            lambda draw: render(dim_warm_light(draw)),
        ),
        _unlike(
            "slow-teacher",
            Scene("pull", "yellow", "dice"),
            "taught slowly",
            "A teacher at tempo 0.45 (corpus 0.7-1.45), the motion played 1.6 times slower: "
            "longer than any corpus recording (3-6 s).",
            lambda draw: render(teacher_tempo(draw, 0.45), slower=1.6),
        ),
        _unlike(
            "fast-teacher",
            Scene("show me", "red", "phone"),
            "taught quickly",
            "A teacher at tempo 2.0 (corpus 0.7-1.45), the motion played in 0.6 of its time: "
            "shorter than any corpus recording (3-6 s).",
            lambda draw: render(teacher_tempo(draw, 2.0), slower=0.6),
        ),
        _unlike(
            "low-resolution",
            Scene("push", "yellow", "banana"),
            "at 160x120 pixels",
            "Frames resized to 160x120, half the corpus's 320x240 each way, as a cheap webcam gives.",
            lambda draw: low_resolution(render(draw)),
        ),
        _unlike(
            "camera-30-fps",
            Scene("slide", "green", "dice"),
            "recorded at 30 fps",
            "Joints and frames at 30 Hz (the corpus: 20); reading resamples them to the model's 20 Hz grid.",
            lambda draw: render(draw, fps=30.0),
        ),
    )


EXAMPLES: dict[str, Example] = {e.name: e for e in _catalogue()}


def write_example(name: str, path: Path) -> Path:
    """Render example `name` and write it as a format-v1 .zip at `path` (atomically)."""
    if name not in EXAMPLES:
        raise KeyError(f"no example {name!r}; examples: {', '.join(EXAMPLES)}")
    return write_zip(EXAMPLES[name].recording(), path)
