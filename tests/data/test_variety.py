"""The wide variety: setups over their ranges, motions that follow them, forms the camera draws."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from data.camera import render_frames
from data.motion import Teacher, generate_motion
from data.nao import JOINT_LIMITS, forward_kinematics
from data.scenario import Scene, all_scenes
from data.setup import PAPER_SETUP, Setup
from data.variety import (
    AZIMUTH,
    POSTURE_FAMILIES,
    TABLE_BAND,
    WIDE_DURATION,
    labels,
    posture,
    posture_family,
    sample_appearance,
    sample_setup,
    sample_teacher,
)
from data.world import PAPER_WORLD, World
from model.encoding.vision import encode_frames_found

SHOULDER = np.array([0.0, -0.098, 0.100])


def _setups(n: int = 60) -> list[Setup]:
    return [sample_setup(np.random.default_rng(k)) for k in range(n)]


def test_same_stream_gives_the_same_setup_and_others_differ() -> None:
    assert sample_setup(np.random.default_rng(4)) == sample_setup(np.random.default_rng(4))
    assert sample_setup(np.random.default_rng(4)) != sample_setup(np.random.default_rng(5))


def test_setups_span_the_table_band_the_annulus_and_both_sides() -> None:
    setups = _setups()
    heights = np.array([s.world.table_z for s in setups])
    assert TABLE_BAND[0] <= heights.min() < -0.09 and -0.04 < heights.max() <= TABLE_BAND[1]
    xy = np.array([s.world.object_home for s in setups])
    azimuth = np.arctan2(xy[:, 1] - SHOULDER[1], xy[:, 0])
    assert azimuth.min() < -0.4 and azimuth.max() > 0.3  # right and left of straight ahead
    assert azimuth.min() >= AZIMUTH[0] - 1e-9 and azimuth.max() <= AZIMUTH[1] + 0.2
    assert np.all(xy[:, 0] >= 0.065)  # never inside the torso
    for s in setups:  # the object stands where the hand reaches just above the table
        rel = np.append(np.asarray(s.world.object_home) - SHOULDER[:2], s.world.table_z + 0.02 - SHOULDER[2])
        assert np.linalg.norm(rel) < 0.216
    sizes = [s.world.size_scale for s in setups]
    assert 0.75 <= min(sizes) < 0.85 and 1.15 < max(sizes) <= 1.25


def test_postures_lie_within_the_joint_limits_in_their_family() -> None:
    setups = _setups()
    assert {s.posture_family for s in setups} == set(POSTURE_FAMILIES)
    for s in setups:
        for q in (s.start, np.array(s.rest_posture)):
            assert np.all(q >= JOINT_LIMITS[:, 0]) and np.all(q <= JOINT_LIMITS[:, 1])
        assert posture_family(forward_kinematics(s.start)["hand"], s.world.table_z) == s.posture_family
    rng = np.random.default_rng(0)
    hand = forward_kinematics(np.array(posture(rng, "low-out", -0.07)))["hand"]
    assert -0.07 + 0.04 < hand[2] <= -0.07 + 0.10 and hand[1] < -0.16


def _wide_motion(scene: Scene, k: int, setup: Setup | None = None):
    rng = np.random.default_rng([k, 1])
    setup = setup or sample_setup(np.random.default_rng([k, 2]))
    return setup, generate_motion(scene, sample_teacher(rng), np.random.default_rng([k, 3]), setup)


def test_wide_motions_start_in_the_setups_posture_last_2_to_8_s_and_stay_above_the_table() -> None:
    durations = []
    for k, scene in enumerate(all_scenes()[::4]):
        setup, m = _wide_motion(scene, k)
        durations.append(m.duration)
        assert WIDE_DURATION[0] <= m.duration <= WIDE_DURATION[1]
        np.testing.assert_allclose(m.joints[0], setup.start, atol=0.25 + 1e-9)  # one frame from it
        assert np.abs(np.diff(m.joints, axis=0)).max() < 0.35  # smooth, as the paper's motions
        assert np.all(m.joints >= JOINT_LIMITS[:, 0]) and np.all(m.joints <= JOINT_LIMITS[:, 1])
        assert m.hand[:, 2].min() > setup.world.table_z
        if scene.action != "show me":  # the object is moved, roughly along the instruction's axis
            assert np.linalg.norm(m.object_xy[-1] - m.object_xy[0]) > 0.01
        else:
            np.testing.assert_array_equal(m.object_xy[-1], m.object_xy[0])
    assert min(durations) < 3.0 or max(durations) > 6.0  # beyond the paper's 3-6 s


def test_the_ik_preference_chooses_elbow_high_or_low_for_the_same_hand_path() -> None:
    base = sample_setup(np.random.default_rng(3))
    scene = Scene("push", "red", "dice")
    elbows = {}
    for name, yaw in (("high", -1.4), ("low", 1.4)):
        setup = Setup(**{**base.__dict__, "ik_preference": (-0.3, yaw)})
        _, m = _wide_motion(scene, 0, setup)
        middle = m.joints[len(m.joints) // 2]
        elbows[name] = (middle[2], forward_kinematics(middle)["elbow"][2])
        assert np.linalg.norm(m.hand - m.path, axis=1).max() < 0.03
    assert elbows["high"][0] < 0 < elbows["low"][0]  # RElbowYaw on either side
    assert elbows["high"][1] > elbows["low"][1]  # and the elbow higher


def test_manners_perform_the_same_instruction_along_other_paths() -> None:
    base = sample_setup(np.random.default_rng(8))
    for action in ("pull", "push", "show me", "slide"):
        paths = []
        for manner in range(3):
            setup = Setup(**{**base.__dict__, "manner": manner, "pause": 0.0})
            _, m = _wide_motion(Scene(action, "blue", "phone"), 5, setup)
            paths.append(m.path)
            moved = m.object_xy[-1] - m.object_xy[0]
            if action == "pull":
                assert moved[0] < -0.01
            elif action == "push":
                assert moved[0] > 0.01
            elif action == "slide":
                assert moved[1] > 0.01
        n = min(len(p) for p in paths)
        assert (
            np.abs(paths[0][:n] - paths[1][:n]).max() > 0.01
            and np.abs(paths[0][:n] - paths[2][:n]).max() > 0.01
        )


def test_a_pause_halts_the_object_halfway() -> None:
    base = sample_setup(np.random.default_rng(2))
    setup = Setup(**{**base.__dict__, "pause": 0.8, "manner": 0})
    _, m = _wide_motion(Scene("push", "green", "apple"), 1, setup)
    speed = np.linalg.norm(np.diff(m.object_xy, axis=0), axis=1) * 20
    moving = np.flatnonzero(speed > 0.005)
    still = np.flatnonzero(speed[moving[0] : moving[-1]] < 1e-4)
    assert len(still) >= 10  # half a second or more at rest between the two halves of the push


def test_the_paper_setup_is_the_paper_world_and_posture() -> None:
    assert PAPER_SETUP.world == PAPER_WORLD and PAPER_SETUP.duration == (3.0, 6.0)
    assert PAPER_SETUP.ik_anchor() is None and PAPER_SETUP.pause == 0.0 and PAPER_SETUP.manner == 0
    s = sample_setup(np.random.default_rng(1))
    assert Setup.from_dict(s.to_dict()) == s and World.from_dict(s.world.to_dict()) == s.world


@pytest.mark.parametrize(
    ("shape", "world", "pips", "form"),
    [
        ("apple", World(apple_stem=False), 3, "apple-no-stem"),
        ("dice", World(dice_round=0.4), 0, "dice-rounded-plain"),
        ("dice", World(size_scale=1.2), 5, "dice-sharp-pips"),
        ("phone", World(phone_screen="none", phone_thickness=0.008), 3, "phone-none-thin"),
    ],
)
def test_forms_are_named_and_drawn(shape: str, world: World, pips: int, form: str) -> None:
    scene = Scene("show me", "red", shape)
    setup = Setup(world=world)
    m = generate_motion(scene, Teacher.sample(np.random.default_rng(0)), np.random.default_rng(1), setup)
    app = sample_appearance(np.random.default_rng(2), world)
    assert world.form(shape, app.banana_bend, pips) == form
    a = render_frames(scene, m, dataclasses.replace(app, dice_pips=pips), world)[:3]
    b = render_frames(scene, m, dataclasses.replace(app, dice_pips=pips), PAPER_WORLD)[:3]
    assert a.shape == (3, 240, 320, 3) and not np.array_equal(a, b)
    _, found = encode_frames_found(a, workers=1)
    assert found.all()


def test_wide_camera_looks_at_the_object_and_the_labels_name_the_regions() -> None:
    setup = sample_setup(np.random.default_rng(6))
    scene = Scene("slide", "yellow", "banana")
    teacher = sample_teacher(np.random.default_rng(7))
    m = generate_motion(scene, teacher, np.random.default_rng(8), setup)
    app = sample_appearance(np.random.default_rng(9), setup.world)
    assert 45.0 <= np.rad2deg(app.hfov) <= 75.0 and abs(app.camera_roll) <= 0.12
    _, found = encode_frames_found(render_frames(scene, m, app, setup.world), workers=1)
    assert found.mean() > 0.9
    tags = labels(scene, setup, teacher, app, len(m.joints))
    assert tags["table_z"] == round(setup.world.table_z, 4) and tags["posture_family"] == setup.posture_family
    assert tags["elbow"] in ("high", "middle", "low") and tags["form"].startswith("banana-")
    assert 0.45 <= tags["tempo"] <= 2.0 and tags["duration_s"] == round(len(m.joints) / 20, 2)
