"""Camera renderer: format, determinism, object colour, saturation contrast, motion in the image."""

from __future__ import annotations

import json
from dataclasses import replace

import cv2
import numpy as np
import pytest

from data.camera import Appearance, project, render_frames
from data.motion import Motion, Teacher, generate_motion
from data.scenario import COLOURS, SHAPES, Scene
from data.world import COLOUR_HUE, TABLE_Z


def _clean(app: Appearance) -> Appearance:
    """No noise, blur, jitter or colour cast: what the colour test needs."""
    return replace(
        app, noise_sigma=0.0, blur_sigma=0.0, shake=0.0, white_balance=(1.0, 1.0, 1.0), exposure=1.0
    )


def _at(motion: Motion, steps: list[int]) -> Motion:
    """The motion reduced to a few time steps (keeps the tests fast)."""
    return replace(
        motion,
        joints=motion.joints[steps],
        hand=motion.hand[steps],
        path=motion.path[steps],
        object_xy=motion.object_xy[steps],
        object_yaw=motion.object_yaw[steps],
        contact=motion.contact[steps],
    )


def _motion(scene: Scene, seed: int, retreat: float | None = None) -> Motion:
    teacher = Teacher.sample(np.random.default_rng(seed))
    if retreat is not None:
        teacher = replace(teacher, retreat=retreat)
    return generate_motion(scene, teacher, np.random.default_rng(seed + 1))


def _saturated_blob(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroid (x, y) and pixel mask of the largest strongly saturated region."""
    hsv = cv2.cvtColor(frame, cv2.COLOR_RGB2HSV)
    mask = ((hsv[..., 1] > 128) & (hsv[..., 2] > 40)).astype(np.uint8)
    count, labels, stats, centroids = cv2.connectedComponentsWithStats(mask)
    assert count > 1, "no saturated region in the frame"
    best = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    return centroids[best], labels == best


def test_frames_are_uint8_rgb_320x240_one_per_time_step() -> None:
    scene = Scene("push", "red", "dice")
    motion = _motion(scene, 0)
    frames = render_frames(scene, motion, Appearance.sample(np.random.default_rng(0)))
    assert frames.dtype == np.uint8
    assert frames.shape == (len(motion.joints), 240, 320, 3)


def test_rendering_is_deterministic_for_an_appearance() -> None:
    scene = Scene("slide", "green", "banana")
    motion = _motion(scene, 1)
    app = Appearance.sample(np.random.default_rng(5))
    np.testing.assert_array_equal(render_frames(scene, motion, app), render_frames(scene, motion, app))
    other = render_frames(scene, motion, Appearance.sample(np.random.default_rng(6)))
    assert not np.array_equal(other, render_frames(scene, motion, app))


@pytest.mark.parametrize("colour", COLOURS)
def test_object_pixels_have_the_colour_s_hue(colour: str) -> None:
    for k, shape in enumerate(SHAPES):
        scene = Scene("show me", colour, shape)
        app = _clean(Appearance.sample(np.random.default_rng(100 + k)))
        frame = render_frames(scene, _at(_motion(scene, k), [0]), app)[0]  # the arm is at its start
        _, blob = _saturated_blob(frame)
        hsv = cv2.cvtColor(frame, cv2.COLOR_RGB2HSV_FULL)  # hue 0..255 for 0..360 degrees
        hue = hsv[..., 0][blob].astype(float) * 360.0 / 256.0
        mean_angle = np.degrees(np.angle(np.mean(np.exp(1j * np.radians(hue))))) % 360.0
        expected, tolerance = COLOUR_HUE[colour]
        gap = abs((mean_angle - expected + 180.0) % 360.0 - 180.0)
        assert gap < tolerance + 8.0, (shape, mean_angle)
        assert blob.sum() > 150  # a real object, not a few stray pixels


def test_the_most_saturated_region_is_the_object_under_wide_appearance_variation() -> None:
    for seed in range(24):
        scene = Scene("pull", COLOURS[seed % 4], SHAPES[(seed // 4) % 4])
        motion = _motion(scene, seed)
        app = Appearance.sample(np.random.default_rng(1000 + seed))
        frame = render_frames(scene, _at(motion, [0]), app)[0]
        _, blob = _saturated_blob(frame)
        x, y, w, h = cv2.boundingRect(blob.astype(np.uint8))
        u, v = project(app, np.append(motion.object_xy[0], TABLE_Z + 0.01))[0]
        assert x - 3 <= u <= x + w + 3 and y - 3 <= v <= y + h + 3, (seed, (x, y, w, h), (u, v))
        assert blob.sum() > 150


@pytest.mark.parametrize("action", ["pull", "push", "slide", "show me"])
def test_the_object_moves_in_the_image_the_way_the_action_moves_it(action: str) -> None:
    for k, shape in enumerate(("apple", "dice")):
        scene = Scene(action, "blue", shape)
        motion = _motion(scene, 20 + k, retreat=1.0)
        app = _clean(Appearance.sample(np.random.default_rng(200 + k)))
        frames = render_frames(scene, _at(motion, [0, len(motion.joints) - 1]), app)
        start, _ = _saturated_blob(frames[0])
        end, _ = _saturated_blob(frames[-1])
        moved = end - start
        world = {"pull": [-0.05, 0.0], "push": [0.05, 0.0], "slide": [0.0, 0.05], "show me": [0, 0]}[action]
        a = np.append(motion.object_xy[0], TABLE_Z)
        expected = project(app, a + np.append(world, 0.0))[0] - project(app, a)[0]
        if action == "show me":
            assert np.linalg.norm(moved) < 3.0
        else:
            cosine = moved @ expected / (np.linalg.norm(moved) * np.linalg.norm(expected))
            assert cosine > 0.8 and np.linalg.norm(moved) > 8.0, (shape, moved, expected)


def test_appearance_survives_a_json_round_trip() -> None:
    app = Appearance.sample(np.random.default_rng(4))
    assert Appearance.from_dict(json.loads(json.dumps(app.to_dict()))) == app
