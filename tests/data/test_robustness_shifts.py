"""The robustness benchmark's shifts (benchmarks/shifts.py): each one yields a valid format-v1
recording, and each moves its own parameters outside what the corpus samples, and only those."""

from __future__ import annotations

import dataclasses
import zipfile
from functools import cache

import numpy as np
import pytest

from benchmarks.shifts import (
    SHIFTS,
    VARIANTS,
    Plan,
    assign_variants,
    make_plan,
    make_recording,
    scene_order,
    simulate,
    write_recording,
)
from data.camera import Appearance, head_angles, project
from data.motion import MAX_DURATION_S, MIN_DURATION_S, Teacher
from data.recording import Recording, read_recording
from data.scenario import ACTIONS, COLOURS, SHAPES
from data.world import OBJECT_HOME, TABLE_Z

SEED = 1
DRAWS = 400  # sampler draws that stand for "the corpus's range"
NUMBERS = range(6)  # recordings checked per variant

# Parameters each shift may change; everything else must equal the in-distribution draw.
OWN_FIELDS: dict[str, set[str]] = {
    "in_distribution": set(),
    "camera_pose": {"hfov", "camera_offset", "head_yaw", "head_pitch", "camera_roll"},
    "lighting": {"exposure", "ambient", "white_balance"},
    "table": {"table_kind", "table_hsv"},
    "teacher": {"teacher", "time_scale"},
    "resolution": {"width", "height"},
    "noise_blur": {"noise_sigma", "blur_sigma"},
    "fps": {"joint_rate", "frame_rate", "meta_fps"},
}


@cache
def _appearances() -> tuple[Appearance, ...]:
    return tuple(Appearance.sample(np.random.default_rng([7, i])) for i in range(DRAWS))


@cache
def _teachers() -> tuple[Teacher, ...]:
    return tuple(Teacher.sample(np.random.default_rng([7, i])) for i in range(DRAWS))


def _range(values: list[float]) -> tuple[float, float]:
    return float(np.min(values)), float(np.max(values))


def _outside(value: float, values: list[float]) -> bool:
    low, high = _range(values)
    return value < low or value > high


def _object_uv(app: Appearance) -> np.ndarray:
    return project(app, [[*OBJECT_HOME, TABLE_Z]])[0] / [app.width, app.height]


def _plans(shift: str) -> list[Plan]:
    order = scene_order()
    return [make_plan(shift, order[k], k, SEED, v) for v in VARIANTS[shift] for k in NUMBERS]


def _changed(plan: Plan) -> set[str]:
    """Names of the plan's fields (appearance fields by their own name) that differ from the
    in-distribution plan of the same scene and number."""
    base = make_plan("in_distribution", plan.scene, plan.number, SEED)
    changed = {
        f.name
        for f in dataclasses.fields(Appearance)
        if getattr(plan.appearance, f.name) != getattr(base.appearance, f.name)
    }
    for name in ("teacher", "time_scale", "joint_rate", "frame_rate", "meta_fps"):
        if getattr(plan, name) != getattr(base, name):
            changed.add(name)
    return changed


@pytest.mark.parametrize("shift", SHIFTS)
def test_each_shift_changes_only_its_own_parameters(shift: str) -> None:
    for plan in _plans(shift):
        changed = _changed(plan)
        assert changed <= OWN_FIELDS[shift], (
            f"{plan.name} ({plan.variant}) also changed {changed - OWN_FIELDS[shift]}"
        )
        assert bool(changed) == (shift != "in_distribution"), f"{plan.name} ({plan.variant}) changed nothing"


def test_camera_pose_lies_outside_the_sampled_poses() -> None:
    apps = _appearances()
    hfov = [a.hfov for a in apps]
    side = [a.camera_offset[1] for a in apps]
    height = [a.camera_offset[2] for a in apps]
    roll = [abs(a.camera_roll) for a in apps]
    uv = np.array([_object_uv(a) for a in apps])
    for plan in _plans("camera_pose"):
        app = plan.appearance
        if plan.variant == "fov":
            assert _outside(app.hfov, hfov)
        elif plan.variant == "displaced":
            assert _outside(app.camera_offset[1], side) and _outside(app.camera_offset[2], height)
        elif plan.variant == "off-centre":
            u, v = _object_uv(app)
            assert _outside(u, list(uv[:, 0])) or _outside(v, list(uv[:, 1]))
            assert 0.1 < u < 0.9 and 0.1 < v < 0.9, "the object must stay in view"
        else:
            assert abs(app.camera_roll) > max(roll)


def test_lighting_table_noise_and_resolution_lie_outside_the_sampled_looks() -> None:
    apps = _appearances()
    exposure = [a.exposure for a in apps]
    gains = [g for a in apps for g in a.white_balance]
    for plan in _plans("lighting"):
        app = plan.appearance
        if plan.variant in ("dark", "bright"):
            assert _outside(app.exposure, exposure)
        else:
            assert any(_outside(g, gains) for g in app.white_balance)
    for plan in _plans("table"):
        hue, sat, val = plan.appearance.table_hsv
        same_kind = [a.table_hsv for a in apps if a.table_kind == plan.appearance.table_kind]
        assert _outside(sat, [s for _, s, _ in same_kind]) or _outside(val, [v for _, _, v in same_kind])
    noise, blur = [a.noise_sigma for a in apps], [a.blur_sigma for a in apps]
    for plan in _plans("noise_blur"):
        app = plan.appearance
        assert _outside(app.noise_sigma, noise) or _outside(app.blur_sigma, blur)
        assert ("noise" in plan.variant) == _outside(app.noise_sigma, noise)
        assert ("blur" in plan.variant) == _outside(app.blur_sigma, blur)
    for plan in _plans("resolution"):
        assert (plan.appearance.width, plan.appearance.height) in ((640, 480), (160, 120))


def test_teacher_shift_leaves_the_sampled_styles_and_durations() -> None:
    teachers = _teachers()
    field = {f.name: [getattr(t, f.name) for t in teachers] for f in dataclasses.fields(Teacher)}
    order = scene_order()
    for plan in _plans("teacher"):
        t = plan.teacher
        if plan.variant == "slow":
            assert _outside(t.tempo, field["tempo"]) and plan.time_scale > 1.0
        elif plan.variant == "fast":
            assert _outside(t.tempo, field["tempo"]) and plan.time_scale < 1.0
        elif plan.variant == "large":
            assert _outside(t.amplitude, field["amplitude"]) and _outside(
                t.approach_height, field["approach_height"]
            )
        else:
            assert _outside(t.hesitation, field["hesitation"]) and _outside(t.tremor, field["tremor"])
    slow = simulate(make_plan("teacher", order[0], 0, SEED, "slow"))
    fast = simulate(make_plan("teacher", order[1], 1, SEED, "fast"))
    assert slow.duration > MAX_DURATION_S and fast.duration < MIN_DURATION_S  # the corpus lies within


def test_head_angles_reproduce_the_sampled_camera_pose() -> None:
    """The displaced camera is re-aimed by `head_angles`, the same solve `Appearance.sample` does."""
    rng, again = np.random.default_rng(5), np.random.default_rng(5)
    app = Appearance.sample(rng)
    again.uniform(52.0, 70.0)  # hfov
    offset = tuple(float(v) for v in again.uniform([-0.02, -0.02, -0.015], [0.02, 0.02, 0.03]))
    aim = np.array([0.13 + again.uniform(-0.02, 0.02), -0.105 + again.uniform(-0.025, 0.025), TABLE_Z])
    assert head_angles(aim, offset) == pytest.approx((app.head_yaw, app.head_pitch), abs=1e-12)


def test_scenes_and_variants_are_spread_evenly() -> None:
    order = scene_order()
    assert len(set(order)) == 64
    for prefix in (16, 32):
        for values, pick in ((ACTIONS, "action"), (COLOURS, "colour"), (SHAPES, "shape")):
            counts = [sum(getattr(s, pick) == v for s in order[:prefix]) for v in values]
            assert counts == [prefix // 4] * 4
    variants = assign_variants("camera_pose", 32, SEED)
    assert sorted(set(variants)) == sorted(VARIANTS["camera_pose"])
    assert all(variants.count(v) == 8 for v in VARIANTS["camera_pose"])


# One cheap variant per shift, rendered short (20 steps: 1 s), written as .zip and read back.
CHEAP = {shift: VARIANTS[shift][-1] for shift in SHIFTS}


@pytest.mark.parametrize("shift", [s for s in SHIFTS if s != "fps"])
def test_each_shift_reads_back_as_a_valid_recording(shift: str) -> None:
    plan = make_plan(shift, scene_order()[5], 5, SEED, CHEAP[shift])
    rec = make_recording(plan, steps=20)
    assert isinstance(rec, Recording) and rec.fps == 20.0 and rec.steps == 20
    assert rec.utterance == plan.scene.utterance
    assert rec.frames.shape[1:] == (plan.appearance.height, plan.appearance.width, 3)
    assert np.isfinite(rec.joints).all()
    assert rec.frames.std() > 5.0  # a rendered scene, not a blank image


def test_fps_shift_writes_50_hz_joints_and_10_fps_frames_read_back_at_20_hz(tmp_path) -> None:
    plan = make_plan("fps", scene_order()[2], 2, SEED, "meta fps")
    path = write_recording(plan, tmp_path / "fps.zip", steps=24)  # 1.15 s
    with zipfile.ZipFile(path) as archive:
        rows = archive.read("joints.csv").decode().strip().splitlines()[1:]
        frames = [n for n in archive.namelist() if n.startswith("frames/")]
    times = np.array([float(r.split(",")[0]) for r in rows])
    assert np.allclose(np.diff(times), 1 / 50) and len(frames) == 12
    rec = read_recording(path, path.name)
    assert rec.fps == 20.0 and rec.steps == 23 and len(rec.frames) == 23  # the 20 Hz grid over 1.14 s
    assert rec.utterance == plan.scene.utterance
    # nearest frame: the 12 frames at 10 fps fill the 23 steps, each used once or twice
    assert len({frame.tobytes() for frame in rec.frames}) == 12
