"""Familiarity: training recordings score 1, recordings unlike them score near 0, the calibration
is the fraction of training nearest-neighbour distances at least as large, warnings name the cause."""

from __future__ import annotations

import numpy as np
import pytest

from data.corpus import load_corpus
from data.scenario import ACTIONS, COLOURS, SHAPES
from data.world import FPS
from model.familiarity import Familiarity, vision_columns


def _parity(scene) -> int:
    return (ACTIONS.index(scene.action) + COLOURS.index(scene.colour) + SHAPES.index(scene.shape)) % 2


@pytest.fixture(scope="module")
def split():
    """The shipped corpus split by scene: half the combinations train, the other half are held out
    (every action, colour and shape is in both halves)."""
    entries = load_corpus().entries
    return [e for e in entries if _parity(e.scene) == 0], [e for e in entries if _parity(e.scene) == 1]


@pytest.fixture(scope="module")
def fam(split) -> Familiarity:
    train, _ = split
    return Familiarity.fit(
        [e.proprioception for e in train],
        [e.vision for e in train],
        [e.object_found for e in train],
        [e.id for e in train],
        vision_columns=21,
    )


def test_a_training_recording_is_fully_familiar_and_raises_no_warning(fam, split) -> None:
    for e in split[0][:8]:
        assert fam.score(e.proprioception, e.vision) == {"proprioception": 1.0, "vision": 1.0}
        assert fam.warnings(e.proprioception, e.vision, e.object_found, FPS) == []


def test_held_out_scenes_score_like_the_calibration_says(fam, split) -> None:
    """A new scene of the same corpus is what the leave-one-scene-out calibration models: its
    scores spread over (0, 1], 0.5-0.75 on average, and none of them is far enough for a warning."""
    test = split[1]
    scores = np.array([list(fam.score(e.proprioception, e.vision).values()) for e in test])
    assert np.all((scores > 0) & (scores <= 1))
    assert 0.4 < scores.mean() < 0.85 and scores.min() < 0.1
    assert all(fam.warnings(e.proprioception, e.vision, e.object_found, FPS) == [] for e in test)


def test_objects_never_seen_are_unfamiliar_to_vision_only() -> None:
    """Trained without bananas and phones, their recordings score low on vision, not on the arm."""
    entries = load_corpus().entries
    seen = [e for e in entries if e.scene.shape in ("apple", "dice")]
    unseen = [e for e in entries if e.scene.shape not in ("apple", "dice")]
    fam = Familiarity.fit(
        [e.proprioception for e in seen], [e.vision for e in seen], ids=[e.id for e in seen]
    )
    scores = np.array([list(fam.score(e.proprioception, e.vision).values()) for e in unseen])
    assert scores[:, 1].mean() < 0.1 < 0.3 < scores[:, 0].mean()


def test_calibration_is_the_fraction_of_neighbour_distances_at_least_as_large(fam) -> None:
    """Per aspect p_b = (1 + #{r_ib >= d_b}) / (n + 1); the sense takes min(1, B * min_b p_b)."""
    sense = fam.proprioception_
    n, aspects = sense.calibration.shape
    assert aspects == 3 and sense.familiarity(np.zeros(aspects)) == 1.0
    beyond = sense.calibration.max(axis=0) * 1.01
    assert sense.familiarity(beyond) == pytest.approx(aspects / (n + 1))
    r = np.sort(sense.calibration[:, 0])
    for i in (0, n // 4, n // 2, n - 1):
        d = np.array([r[i], 0.0, 0.0])  # only the postures differ
        p = (1 + np.count_nonzero(r >= r[i])) / (n + 1)
        assert sense.familiarity(d) == pytest.approx(min(1.0, aspects * p))
    grid = [np.array([x, x / 2, x / 10]) for x in np.linspace(0, 2 * beyond.max(), 50)]
    assert np.all(np.diff([sense.familiarity(d) for d in grid]) <= 0)  # farther is never more familiar


def test_shifted_postures_are_unfamiliar_and_said_so(fam, split) -> None:
    e = split[0][0]
    shifted = np.clip(e.proprioception + np.array([0.0, 0.15, 0.1, 0.0, 0.0], dtype=np.float32), 0, 1)
    score = fam.score(shifted, e.vision)
    assert score["proprioception"] < 0.05 and score["vision"] == 1.0
    warnings = fam.warnings(shifted, e.vision, e.object_found, FPS)
    assert warnings == ["the arm's postures are far outside what the model learned from"]


def test_a_recording_three_times_longer_is_unfamiliar_and_said_so(fam, split) -> None:
    e = split[0][0]
    slow = np.repeat(e.proprioception, 3, axis=0)
    vision = np.repeat(e.vision, 3, axis=0)
    assert fam.score(slow, vision)["proprioception"] < 0.05
    longest = max(len(t.proprioception) for t in split[0]) / FPS
    said = fam.warnings(slow, vision, 1.0, FPS)
    numbers = f"({len(slow) / FPS:.1f} s against at most {longest:.1f} s)"
    assert f"the recording is much longer than any the model learned from {numbers}" in said
    steps = fam.warnings(slow, vision)  # without a frame rate: in steps
    assert any(f"({len(slow)} steps against at most" in w for w in steps)


def test_a_camera_view_unlike_the_training_set_is_said(fam, split) -> None:
    e = split[0][0]
    white = e.vision.copy()
    white[:, 16:19] = 1.0  # a white object: no corpus colour is that bright
    assert fam.score(e.proprioception, white)["vision"] < 0.05
    said = fam.warnings(e.proprioception, white, 1.0)
    assert said == ["the object's colour is unlike every colour the model learned from"]
    corner = e.vision.copy()
    corner[:, 19:21] = 0.05  # in the image's top left corner
    said = fam.warnings(e.proprioception, corner, 1.0)
    assert said == ["the object is where the camera never saw one in the recordings the model learned from"]
    assert fam.score(e.proprioception, corner)["proprioception"] == 1.0


def test_joints_at_their_limits_and_missing_objects_are_counted(fam, split) -> None:
    e = split[0][0]
    prop = e.proprioception.copy()
    steps = len(prop)
    at_limit = round(0.3 * steps)
    prop[:at_limit, 4] = 1.0
    said = fam.warnings(prop, e.vision, 0.6, FPS)
    assert f"the joint angles sit at their limits in {100 * at_limit / steps:.0f} % of the steps" in said
    assert "no object found in 40 % of the frames" in said
    quiet = fam.warnings(e.proprioception, e.vision, 0.95, FPS)  # 5 %: below MISSING_FRAMES
    assert quiet == []


def test_arrays_round_trip_to_the_same_answers(fam, split) -> None:
    again = Familiarity.from_arrays(fam.arrays())
    for e in split[1][:6]:
        assert again.score(e.proprioception, e.vision) == fam.score(e.proprioception, e.vision)
        found = 0.5
        assert again.warnings(e.proprioception, e.vision, found, FPS) == fam.warnings(
            e.proprioception, e.vision, found, FPS
        )
    assert again.missing_ == fam.missing_ and again.steps_ == fam.steps_


def test_the_vision_columns_the_model_reads(split) -> None:
    train = split[0][:16]
    fam19 = Familiarity.fit([e.proprioception for e in train], [e.vision for e in train], vision_columns=19)
    e = train[0]
    assert fam19.score(e.proprioception, e.vision[:, :19]) == fam19.score(e.proprioception, e.vision)
    assert vision_columns({"config": {"visual": {"io": 19}}}) == 19
    assert vision_columns({"peer_config": {"vision": 19}}) == 19 and vision_columns({}) is None
    with pytest.raises(ValueError, match=r"\[T, >=21\]"):
        Familiarity.fit([e.proprioception] * 2, [e.vision] * 2, vision_columns=21).score(
            e.proprioception, e.vision[:, :19]
        )


def test_bad_inputs_are_named(fam, split) -> None:
    e = split[0][0]
    with pytest.raises(ValueError, match="at least two training recordings"):
        Familiarity.fit([e.proprioception], [e.vision])
    with pytest.raises(ValueError, match="proprioception must be a non-empty"):
        fam.score(e.proprioception[:, :3], e.vision)
    bad = e.vision.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        fam.score(e.proprioception, bad)
