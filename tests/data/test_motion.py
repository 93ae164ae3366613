"""Teacher-guided motions: determinism, duration, limits, object movement, the banana exception."""

from __future__ import annotations

import json

import numpy as np
import pytest

from data.motion import Motion, Teacher, generate_motion, retimed
from data.nao import HOME_POSTURE, JOINT_LIMITS, forward_kinematics
from data.scenario import ACTIONS, COLOURS, SHAPES, Scene, all_scenes
from data.world import FPS, TABLE_Z


def _motion(scene: Scene, teacher_seed: int, trial_seed: int) -> Motion:
    teacher = Teacher.sample(np.random.default_rng(teacher_seed))
    return generate_motion(scene, teacher, np.random.default_rng(trial_seed))


def _resampled(joints: np.ndarray, n: int = 100) -> np.ndarray:
    src = np.linspace(0.0, 1.0, len(joints))
    dst = np.linspace(0.0, 1.0, n)
    return np.stack([np.interp(dst, src, joints[:, k]) for k in range(joints.shape[1])], axis=1)


def test_same_seeds_give_identical_motions() -> None:
    a = _motion(Scene("push", "red", "apple"), 3, 11)
    b = _motion(Scene("push", "red", "apple"), 3, 11)
    np.testing.assert_array_equal(a.joints, b.joints)
    np.testing.assert_array_equal(a.object_xy, b.object_xy)
    c = _motion(Scene("push", "red", "apple"), 3, 12)
    assert not np.array_equal(a.joints, c.joints)


def test_every_scene_lasts_3_to_6_seconds_within_joint_limits_from_the_same_start() -> None:
    for scene in all_scenes()[::5]:
        for k in range(2):
            m = _motion(scene, 100 * k + scene.index, scene.index + k)
            assert 3.0 <= m.duration <= 6.0
            assert m.joints.shape == (len(m.joints), 5) and m.fps == FPS
            assert np.all(m.joints >= JOINT_LIMITS[:, 0]) and np.all(m.joints <= JOINT_LIMITS[:, 1])
            assert np.all(np.isfinite(m.joints))
            np.testing.assert_allclose(m.joints[0], HOME_POSTURE, atol=0.05)
            assert m.hand[:, 2].min() > TABLE_Z  # never through the table
            # smooth: no joint jumps more than 0.35 rad between frames (7 rad/s)
            assert np.abs(np.diff(m.joints, axis=0)).max() < 0.35


def test_ik_follows_the_guided_hand_path_within_1cm() -> None:
    worst = 0.0
    for scene in all_scenes()[::3]:
        m = _motion(scene, scene.index, 7 * scene.index)
        errors = np.linalg.norm(m.hand - m.path, axis=1)
        worst = max(worst, float(errors.max()))
        reached = np.array([forward_kinematics(q)["hand"] for q in m.joints[::10]])
        np.testing.assert_allclose(reached, m.hand[::10], atol=1e-9)
    assert worst < 0.01


@pytest.mark.parametrize("action", ACTIONS)
def test_each_action_moves_the_object_the_way_the_instruction_says(action: str) -> None:
    for shape in SHAPES:
        for k in range(3):
            m = _motion(Scene(action, "blue", shape), 10 + k, 20 + k)
            dx, dy = m.object_xy[-1] - m.object_xy[0]
            if action == "pull":  # towards the torso
                assert dx < -0.02 and abs(dy) < abs(dx)
            elif action == "push":  # away from the torso
                assert dx > 0.02 and abs(dy) < abs(dx)
            elif action == "slide":  # to the robot's left
                assert dy > 0.02 and abs(dx) < abs(dy)
            else:  # show me leaves it where it is
                assert abs(dx) < 1e-9 and abs(dy) < 1e-9
                # and the hand ends up near it, pointing from above
                closest = np.linalg.norm(m.hand[:, :2] - m.object_xy[0], axis=1).min()
                assert closest < 0.06


def test_joints_do_not_depend_on_colour() -> None:
    ref = _motion(Scene("pull", "red", "dice"), 5, 9)
    for colour in COLOURS:
        np.testing.assert_array_equal(_motion(Scene("pull", colour, "dice"), 5, 9).joints, ref.joints)


def test_sliding_the_banana_differs_more_than_apple_from_dice() -> None:
    gaps_banana, gaps_dice = [], []
    for k in range(6):
        joints = {s: _resampled(_motion(Scene("slide", "red", s), 30 + k, 40 + k).joints) for s in SHAPES}
        gaps_banana.append(np.abs(joints["banana"] - joints["apple"]).mean())
        gaps_dice.append(np.abs(joints["dice"] - joints["apple"]).mean())
    assert min(gaps_banana) > 2.0 * max(gaps_dice)


def test_teachers_vary_widely() -> None:
    teachers = [Teacher.sample(np.random.default_rng(s)) for s in range(40)]
    durations = [_motion(Scene("push", "green", "phone"), s, s).duration for s in range(12)]
    assert np.ptp([t.tempo for t in teachers]) > 0.5
    assert np.ptp([t.amplitude for t in teachers]) > 0.02
    assert np.ptp(durations) > 1.0


def test_teacher_survives_a_json_round_trip() -> None:
    teacher = Teacher.sample(np.random.default_rng(4))
    assert Teacher.from_dict(json.loads(json.dumps(teacher.to_dict()))) == teacher


def test_a_retimed_motion_keeps_its_path_at_another_speed_and_rate() -> None:
    motion = _motion(Scene("slide", "red", "apple"), 0, 1)
    same = retimed(motion, 1.0)
    assert np.array_equal(same.joints, motion.joints) and np.array_equal(same.contact, motion.contact)
    slow = retimed(motion, 2.0, fps=30.0)
    assert slow.fps == 30.0 and len(slow.joints) == round(len(motion.joints) * 2.0 * 30.0 / FPS)
    assert slow.duration == pytest.approx(2.0 * motion.duration, abs=2 / 30)
    assert np.allclose(slow.joints[0], motion.joints[0]) and np.allclose(slow.joints[-1], motion.joints[-1])
    assert slow.contact.any() == motion.contact.any()
