"""The recordings to try (data/examples.py): corpus exports of each action, and recordings whose
camera, light, teacher tempo, resolution or frame rate lie outside what the corpus samples; each
one deterministic and readable as format v1."""

from __future__ import annotations

import dataclasses
import re
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from data.camera import Appearance, project
from data.corpus import load_corpus
from data.examples import (
    EXAMPLES,
    dim_warm_light,
    draw_for,
    other_camera,
    teacher_tempo,
    write_example,
)
from data.motion import MAX_DURATION_S, MIN_DURATION_S, Teacher
from data.recording import read_recording
from data.scenario import ACTIONS, Scene
from data.world import FPS, OBJECT_HOME, TABLE_Z

DRAWS = 300  # sampler draws that stand for "the corpus's range"
SCENE = Scene("push", "green", "apple")


@cache
def _appearances() -> tuple[Appearance, ...]:
    return tuple(Appearance.sample(np.random.default_rng([3, i])) for i in range(DRAWS))


@cache
def _teachers() -> tuple[Teacher, ...]:
    return tuple(Teacher.sample(np.random.default_rng([3, i])) for i in range(DRAWS))


def _values(field: str, index: int | None = None) -> np.ndarray:
    values = [getattr(a, field) for a in _appearances()]
    return np.array([v[index] for v in values] if index is not None else values, dtype=float)


def test_the_catalogue_offers_each_action_from_the_corpus_and_recordings_unlike_it() -> None:
    examples = list(EXAMPLES.values())
    assert len(examples) >= 6
    assert all(re.fullmatch(r"[a-z0-9-]+", e.name) for e in examples)
    assert all(e.title and e.description for e in examples)
    assert {e.scene.action for e in examples if e.kind == "corpus"} == set(ACTIONS)
    assert all(e.title.startswith(e.scene.utterance[:-1]) for e in examples)
    assert {e.name for e in examples if e.kind == "unlike"} >= {
        "other-camera",
        "dim-warm-light",
        "slow-teacher",
        "fast-teacher",
        "low-resolution",
        "camera-30-fps",
    }


def test_a_corpus_example_is_the_recording_the_corpus_holds() -> None:
    rec = EXAMPLES["corpus-push-blue-dice-1"].recording()
    entry = load_corpus().by_id("push-blue-dice-1")
    assert rec.utterance == entry.utterance == "push the blue dice."
    assert np.allclose(rec.joints, entry.joints) and rec.frames.shape == (len(entry.joints), 240, 320, 3)


def test_another_robots_camera_lies_outside_the_corpus_poses_and_still_sees_the_workspace() -> None:
    base = draw_for(SCENE)
    app = other_camera(base).appearance
    assert np.rad2deg(app.hfov) > np.rad2deg(_values("hfov").max()) + 5
    assert app.camera_offset[1] > _values("camera_offset", 1).max() + 0.02
    assert app.camera_offset[2] > _values("camera_offset", 2).max() + 0.03
    u, v = project(app, np.append(OBJECT_HOME, TABLE_Z))[0]
    assert 0 < u < app.width and 0 < v < app.height  # re-aimed: the object is in the picture
    unchanged = {"hfov", "camera_offset", "head_yaw", "head_pitch"}
    for field in dataclasses.fields(Appearance):
        if field.name not in unchanged:
            assert getattr(app, field.name) == getattr(base.appearance, field.name), field.name


def test_dim_warm_light_lies_outside_the_corpus_exposure_and_white_balance() -> None:
    app = dim_warm_light(draw_for(SCENE)).appearance
    assert app.exposure < _values("exposure").min() and app.ambient < _values("ambient").min()
    assert app.white_balance[0] > _values("white_balance", 0).max()
    assert app.white_balance[2] < _values("white_balance", 2).min()


def test_the_teachers_tempo_lies_outside_the_corpus_teachers_and_nothing_else_changes() -> None:
    base = draw_for(SCENE)
    tempos = np.array([t.tempo for t in _teachers()])
    slow, fast = teacher_tempo(base, 0.45).teacher, teacher_tempo(base, 2.0).teacher
    assert slow.tempo < tempos.min() and fast.tempo > tempos.max()
    assert dataclasses.replace(slow, tempo=base.teacher.tempo) == base.teacher


@pytest.mark.parametrize(
    ("name", "fps", "check"),
    [
        ("fast-teacher", FPS, lambda rec: rec.duration < MIN_DURATION_S),
        ("low-resolution", FPS, lambda rec: rec.frames.shape[1:3] == (120, 160)),
        ("camera-30-fps", 30.0, lambda rec: rec.frames.shape[1:3] == (240, 320)),
        pytest.param("slow-teacher", FPS, lambda rec: rec.duration > MAX_DURATION_S, marks=pytest.mark.slow),
    ],
)
def test_an_example_is_format_v1_and_reads_back_onto_the_20_hz_grid(
    tmp_path: Path, name: str, fps: float, check: object
) -> None:
    rec = EXAMPLES[name].recording()
    assert rec.fps == fps and check(rec)  # type: ignore[operator]
    path = write_example(name, tmp_path / f"{name}.zip")
    back = read_recording(path, path.name)
    assert back.fps == FPS and back.utterance == rec.utterance
    assert abs(back.duration - rec.duration) <= 1.5 / FPS  # resampled, same span
    assert back.frames.shape[1:] == rec.frames.shape[1:]


def test_an_example_is_the_same_bytes_every_time(tmp_path: Path) -> None:
    first = write_example("fast-teacher", tmp_path / "a.zip").read_bytes()
    again = write_example("fast-teacher", tmp_path / "b.zip").read_bytes()
    assert first == again


def test_an_unknown_example_names_the_known_ones(tmp_path: Path) -> None:
    with pytest.raises(KeyError, match="other-camera"):
        write_example("nope", tmp_path / "nope.zip")
    assert not (tmp_path / "nope.zip").exists()
