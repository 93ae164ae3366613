"""Recording format v1: round trips, resampling, and a specific error for each kind of bad input."""

from __future__ import annotations

import io
import json
import re
import zipfile
from pathlib import Path

import cv2
import numpy as np
import pytest

from data.nao import JOINT_LIMITS, JOINT_NAMES
from data.recording import (
    CSV_HEADER,
    FPS,
    Recording,
    RecordingError,
    joints_csv,
    read_recording,
    write_npz,
    write_zip,
)

HEADER = ",".join(CSV_HEADER)


def make_recording(steps: int = 30, height: int = 48, width: int = 64, seed: int = 0) -> Recording:
    """Smooth joints inside the limits and frames with a moving block (so frames differ)."""
    rng = np.random.default_rng(seed)
    mid = JOINT_LIMITS.mean(axis=1)
    half = (JOINT_LIMITS[:, 1] - JOINT_LIMITS[:, 0]) / 4
    t = np.arange(steps) / FPS
    joints = mid + half * np.sin(t[:, None] * 2 + rng.uniform(0, 6, 5))
    frames = np.full((steps, height, width, 3), 40, np.uint8)
    for i in range(steps):
        x = 2 + (i * 37) % (width - 14)
        frames[i, 10:22, x : x + 12] = (200, 30 + i, 60)
    return Recording(joints=joints, frames=frames, fps=FPS, utterance="push the red dice.")


def zip_bytes(files: dict[str, bytes | str], compress: int = zipfile.ZIP_DEFLATED) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compress) as z:
        for name, data in files.items():
            z.writestr(name, data)
    return buf.getvalue()


def png(frame_rgb: np.ndarray) -> bytes:
    return cv2.imencode(".png", cv2.cvtColor(frame_rgb, cv2.COLOR_RGB2BGR))[1].tobytes()


def valid_files(rec: Recording | None = None) -> dict[str, bytes | str]:
    rec = rec or make_recording()
    files: dict[str, bytes | str] = {"joints.csv": joints_csv(rec)}
    for i, frame in enumerate(rec.frames):
        files[f"frames/{i:03d}.png"] = png(frame)
    return files


def npz_bytes(**arrays: object) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def csv_text(rows: list[list[object]], header: str = HEADER) -> str:
    return header + "\n" + "\n".join(",".join(str(v) for v in row) for row in rows) + "\n"


def good_rows(steps: int = 30, rate: float = FPS) -> list[list[object]]:
    mid = JOINT_LIMITS.mean(axis=1)
    return [[i / rate, *mid] for i in range(steps)]


def read_err(data: bytes, filename: str = "rec.zip") -> str:
    with pytest.raises(RecordingError) as info:
        read_recording(data, filename)
    return str(info.value)


# ---------------------------------------------------------------------------------------- round trips


def test_zip_png_round_trip_is_exact(tmp_path: Path) -> None:
    rec = make_recording()
    path = write_zip(rec, tmp_path / "rec.zip", frames_as="png")
    back = read_recording(path, "rec.zip")
    np.testing.assert_array_equal(back.joints, rec.joints)
    np.testing.assert_array_equal(back.frames, rec.frames)
    assert back.utterance == rec.utterance and back.fps == FPS


def test_zip_mp4_round_trip_decodes_close_to_the_original(tmp_path: Path) -> None:
    rec = make_recording(steps=40, height=96, width=128)
    path = write_zip(rec, tmp_path / "rec.zip", frames_as="mp4")
    with zipfile.ZipFile(path) as z:
        assert "video.mp4" in z.namelist()
    back = read_recording(path.read_bytes(), "rec.zip")
    np.testing.assert_array_equal(back.joints, rec.joints)
    assert back.frames.shape == rec.frames.shape
    error = np.abs(back.frames.astype(int) - rec.frames.astype(int)).mean()
    assert error < 6.0  # lossy codec, same content; a frame shift would move the block by 37 px


def test_npz_round_trip_is_exact(tmp_path: Path) -> None:
    rec = make_recording()
    path = write_npz(rec, tmp_path / "rec.npz")
    back = read_recording(path, "rec.npz")
    np.testing.assert_array_equal(back.joints, rec.joints)
    np.testing.assert_array_equal(back.frames, rec.frames)
    assert back.utterance == rec.utterance


def test_writes_are_atomic_and_leave_no_temporary_files(tmp_path: Path) -> None:
    rec = make_recording()
    write_zip(rec, tmp_path / "a.zip")
    write_npz(rec, tmp_path / "a.npz")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.npz", "a.zip"]


def test_npz_is_recognised_by_content_whatever_its_name() -> None:
    rec = make_recording()
    data = npz_bytes(joints=rec.joints, frames=rec.frames)
    back = read_recording(data, "upload.bin")
    np.testing.assert_array_equal(back.frames, rec.frames)
    assert back.utterance is None


def test_joints_at_50_hz_are_interpolated_to_20_hz() -> None:
    rate = 50.0
    t = np.arange(0, 2.0 + 1e-9, 1 / rate)
    mid = JOINT_LIMITS.mean(axis=1)
    rows = [[ti, mid[0] + 0.1 * ti, *mid[1:]] for ti in t]
    rec = make_recording(steps=10)
    files = {"joints.csv": csv_text(rows)} | {f"frames/{i}.png": png(f) for i, f in enumerate(rec.frames)}
    back = read_recording(zip_bytes(files), "rec.zip")
    assert back.steps == 41  # 0.00, 0.05, ..., 2.00 s
    np.testing.assert_allclose(back.joints[:, 0], mid[0] + 0.1 * np.arange(41) / FPS, atol=1e-12)


def test_frames_are_spread_evenly_over_the_joint_span_in_natural_name_order() -> None:
    rec = make_recording(steps=11)  # 11 frames for 0..2 s of joints: one frame per 0.2 s
    files: dict[str, bytes | str] = {"joints.csv": csv_text(good_rows(41))}
    for i, frame in enumerate(rec.frames):
        files[f"frames/f{i}.png"] = png(frame)  # f10 must sort after f9
    back = read_recording(zip_bytes(files), "rec.zip")
    assert back.steps == 41
    np.testing.assert_array_equal(back.frames[0], rec.frames[0])
    np.testing.assert_array_equal(back.frames[40], rec.frames[10])
    np.testing.assert_array_equal(back.frames[17], rec.frames[4])  # 0.85 s -> frame at 0.8 s
    np.testing.assert_array_equal(back.frames[37], rec.frames[9])  # 1.85 s -> frame at 1.8 s


def test_a_recording_in_one_folder_inside_the_zip_is_accepted() -> None:
    files = {f"myrun/{k}": v for k, v in valid_files().items()} | {"__MACOSX/._x": b"junk"}
    assert read_recording(zip_bytes(files), "rec.zip").steps == 30


def test_jpeg_frames_and_meta_json_are_read() -> None:
    rec = make_recording()
    files: dict[str, bytes | str] = {
        "joints.csv": joints_csv(rec),
        "meta.json": '{"utterance": "show me the blue phone."}',
    }
    for i, frame in enumerate(rec.frames):
        files[f"frames/{i:03d}.jpg"] = cv2.imencode(".jpg", frame[..., ::-1])[1].tobytes()
    back = read_recording(zip_bytes(files), "rec.zip")
    assert back.utterance == "show me the blue phone."
    assert np.abs(back.frames.astype(int) - rec.frames.astype(int)).mean() < 5  # RGB order kept


def test_angles_just_outside_a_limit_are_clipped_not_rejected() -> None:
    rows = good_rows()
    rows[3][4] = JOINT_LIMITS[3, 1] + 0.01
    files = valid_files() | {"joints.csv": csv_text(rows)}
    back = read_recording(zip_bytes(files), "rec.zip")
    assert back.joints[3, 3] == JOINT_LIMITS[3, 1]


# ----------------------------------------------------------------------------------- malformed input


def test_empty_file() -> None:
    assert read_err(b"") == "rec.zip is empty (0 bytes)"


def test_not_a_zip_or_npz() -> None:
    msg = read_err(b"hello, this is text", "notes.txt")
    assert "notes.txt is not a recording" in msg and ".zip" in msg and ".npz" in msg


def test_corrupt_archive_with_zip_name() -> None:
    assert "corrupt archive: rec.zip does not start like a zip/npz file" in read_err(
        b"\x00\x01garbage", "rec.zip"
    )


def test_truncated_zip_is_a_corrupt_archive() -> None:
    data = zip_bytes(valid_files())
    assert read_err(data[: len(data) // 2]).startswith("corrupt archive: rec.zip cannot be opened")


def test_corrupted_member_bytes_are_a_corrupt_archive() -> None:
    data = bytearray(zip_bytes({"joints.csv": csv_text(good_rows(200))}))
    start = 30 + len("joints.csv")  # first member's data follows its local header
    data[start + 20 : start + 60] = b"\xff" * 40
    assert "corrupt archive: 'joints.csv' in rec.zip cannot be read" in read_err(bytes(data))


def test_empty_archive() -> None:
    assert read_err(zip_bytes({})) == "rec.zip is an empty archive: it holds no files"


def test_single_npy_file_is_explained() -> None:
    buf = io.BytesIO()
    np.save(buf, np.zeros((3, 5)))
    assert "is a single .npy array" in read_err(buf.getvalue(), "joints.npy")


def test_missing_joints_csv() -> None:
    files = valid_files()
    del files["joints.csv"]
    assert read_err(zip_bytes(files)).startswith(
        "rec.zip has no joints.csv at its top level (it holds: frames/"
    )


def test_missing_column() -> None:
    header = HEADER.replace(",RElbowYaw", "")
    rows = [r[:3] + r[4:] for r in good_rows()]
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows, header)}))
    assert msg.startswith("joints.csv has missing column(s) RElbowYaw; the header must be t,RShoulderPitch")


def test_misspelt_column() -> None:
    header = HEADER.replace("RWristYaw", "RWristYawn")
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(good_rows(), header)}))
    assert "missing column(s) RWristYaw; unknown column(s) 'RWristYawn'" in msg


def test_no_header_row() -> None:
    text = csv_text(good_rows()).split("\n", 1)[1]
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": text}))
    assert msg == f"joints.csv has no header row; its first line must be {HEADER}"


def test_non_numeric_value() -> None:
    rows = good_rows()
    rows[6][4] = "abc"
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows)}))
    assert msg == "joints.csv line 8, column RElbowRoll: 'abc' is not a number"


def test_nan_angle() -> None:
    rows = good_rows()
    rows[2][1] = "nan"
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows)}))
    assert msg == "joints.csv line 4, column RShoulderPitch: 'nan' is not a finite number"


def test_row_with_missing_values() -> None:
    rows = good_rows()
    rows[4] = rows[4][:4]
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows)}))
    assert msg == "joints.csv line 6 has 4 values; expected 6"


def test_angle_outside_the_nao_limit_names_joint_and_limit() -> None:
    rows = good_rows()
    rows[10][2] = -1.9  # RShoulderRoll limit is [-1.3265, 0.3142]
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows)}))
    assert msg == (
        "RShoulderRoll = -1.9000 rad at t = 0.5 s (joints.csv line 12) is outside the NAO joint limit "
        "[-1.3265, 0.3142] rad"
    )


def test_angles_in_degrees_get_a_hint() -> None:
    rows = [[r[0], *np.degrees(np.array(r[1:], dtype=float))] for r in good_rows()]
    rows = [[r[0], 30.0, *r[2:]] for r in rows]
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows)}))
    assert msg.startswith("RShoulderPitch = 30.0000 rad") and "are the angles in degrees?" in msg


def test_time_not_increasing() -> None:
    rows = good_rows()
    rows[5][0] = rows[4][0]
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows)}))
    assert msg == "joints.csv: time goes from 0.2 s (line 6) to 0.2 s (line 7); t must be strictly increasing"


def test_too_short() -> None:
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(good_rows(10))}))
    assert msg == "the recording is too short: 0.45 s (10 steps at 20 Hz); at least 1 s (20 steps) is needed"


def test_too_long() -> None:
    rows = good_rows(2, rate=1 / 31)  # t = 0 and 31 s
    msg = read_err(zip_bytes(valid_files() | {"joints.csv": csv_text(rows)}))
    assert (
        msg == "the recording is too long: 31.00 s (621 steps at 20 Hz); at most 30 s (600 steps) is accepted"
    )


def test_no_frames_at_all() -> None:
    msg = read_err(zip_bytes({"joints.csv": csv_text(good_rows())}))
    assert msg == "rec.zip has no camera frames: add video.mp4 (or video.avi) or images frames/*.png|jpg"


def test_corrupt_video_has_no_decodable_frames() -> None:
    files = {"joints.csv": csv_text(good_rows()), "video.mp4": b"\x00\x00\x00\x18ftypmp42" + b"\x07" * 5000}
    assert read_err(zip_bytes(files)).startswith("video.mp4 has no decodable frames")


def test_image_that_does_not_decode() -> None:
    files = valid_files() | {"frames/000.png": b"\x89PNG\r\n\x1a\n" + b"broken"}
    assert read_err(zip_bytes(files)) == "frames/000.png is not a decodable PNG/JPEG image"


def test_frames_of_different_sizes() -> None:
    files = valid_files() | {"frames/005.png": png(np.zeros((40, 64, 3), np.uint8))}
    msg = read_err(zip_bytes(files))
    assert msg.startswith(
        "frames/005.png is 64x40 but the first frame is 64x48; all frames must have the same size"
    )


def test_frames_too_small() -> None:
    files = {"joints.csv": csv_text(good_rows()), "frames/0.png": png(np.zeros((16, 16, 3), np.uint8))}
    assert (
        read_err(zip_bytes(files)) == "frames/0.png is 16x16 pixels; frames must be at least 32 pixels a side"
    )


def test_frames_absurdly_large_are_rejected_from_the_header() -> None:
    big = np.zeros((1200, 2400, 3), np.uint8)
    files = {"joints.csv": csv_text(good_rows()), "frames/0.png": png(big)}
    msg = read_err(zip_bytes(files))
    assert msg.startswith("frames/0.png is 2400x1200 pixels; frames may be at most 1920x1080")


def test_two_sets_of_frames() -> None:
    files = valid_files() | {"video.mp4": b"whatever"}
    assert (
        read_err(zip_bytes(files))
        == "rec.zip holds more than one set of frames (video.mp4, frames/); keep exactly one"
    )


def test_member_path_with_dotdot() -> None:
    files = valid_files() | {"../../etc/evil.sh": b"rm -rf /"}
    msg = read_err(zip_bytes(files))
    assert msg == (
        "rec.zip contains the unsafe path '../../etc/evil.sh': "
        "member paths must be relative and must not contain '..'"
    )


def test_absolute_member_path() -> None:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr(zipfile.ZipInfo("joints.csv"), csv_text(good_rows()))
        info = zipfile.ZipInfo("x")
        info.filename = "/tmp/evil"  # ZipInfo() strips a leading '/', a hand-made archive need not
        z.writestr(info, b"x")
    assert "contains the unsafe path '/tmp/evil'" in read_err(buf.getvalue())


def zeros_member_zip(megabytes: int) -> bytes:
    """A valid recording plus `megabytes` MB of zeros that deflate to about 1/1000 of that."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in valid_files().items():
            z.writestr(name, data)
        with z.open("extra/zeros.bin", "w", force_zip64=True) as member:
            for _ in range(megabytes):
                member.write(bytes(1024**2))
    return buf.getvalue()


def test_decompression_bomb_total_size_is_rejected_before_decompressing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import data.recording.read as recording

    monkeypatch.setattr(recording, "MAX_UNCOMPRESSED_BYTES", 4 * 1024**2)  # 400 MB in production
    data = zeros_member_zip(6)
    assert len(data) < 100 * 1024
    assert read_err(data) == "rec.zip would unpack to 6 MB, more than the limit of 4 MB (decompression bomb?)"


def test_decompression_bomb_compression_ratio_is_rejected(monkeypatch: pytest.MonkeyPatch) -> None:
    import data.recording.read as recording

    monkeypatch.setattr(recording, "BOMB_MIN_MEMBER_BYTES", 2 * 1024**2)  # 50 MB in production
    msg = read_err(zeros_member_zip(3))
    assert re.fullmatch(
        r"rec.zip: member 'extra/zeros.bin' expands \d+-fold to 3 MB \(decompression bomb\?\)", msg
    )


def test_invalid_meta_json() -> None:
    msg = read_err(zip_bytes(valid_files() | {"meta.json": "{utterance: 'x'}"}))
    assert msg.startswith("meta.json is not valid JSON")


def test_utterance_not_a_string() -> None:
    msg = read_err(zip_bytes(valid_files() | {"meta.json": json.dumps({"utterance": 42})}))
    assert msg == "meta.json: utterance must be a string, got int 42"


def test_meta_fps_not_positive() -> None:
    msg = read_err(zip_bytes(valid_files() | {"meta.json": json.dumps({"fps": 0})}))
    assert msg == "meta.json: fps must be a positive number, got 0"


def test_frames_covering_too_little_of_the_joints() -> None:
    files = valid_files() | {"meta.json": json.dumps({"fps": 200})}  # 30 frames = 0.15 s of 1.45 s
    msg = read_err(zip_bytes(files))
    assert msg.startswith("frames/: the frames cover 0.14 s but the joints cover 1.45 s")


def test_npz_missing_frames() -> None:
    msg = read_err(npz_bytes(joints=make_recording().joints), "rec.npz")
    assert msg.startswith("rec.npz has no 'frames' array (it holds: joints)")


def test_npz_with_object_array_is_refused_without_unpickling() -> None:
    rec = make_recording()
    data = npz_bytes(joints=rec.joints, frames=rec.frames, utterance=np.array(["x", 1], dtype=object))
    msg = read_err(data, "rec.npz")
    assert msg.startswith(
        "rec.npz: array 'utterance' holds Python objects (a pickle), which are never loaded"
    )


def test_npz_frames_of_wrong_dtype() -> None:
    rec = make_recording()
    msg = read_err(npz_bytes(joints=rec.joints, frames=rec.frames / 255.0), "rec.npz")
    assert msg.startswith("rec.npz: frames must be uint8 RGB (0..255), got dtype float64")


def test_npz_grey_frames_have_the_wrong_shape() -> None:
    rec = make_recording()
    msg = read_err(npz_bytes(joints=rec.joints, frames=rec.frames[..., 0]), "rec.npz")
    assert msg == "rec.npz: frames must have shape T x H x W x 3 (RGB), got (30, 48, 64)"


def test_npz_length_mismatch() -> None:
    rec = make_recording()
    msg = read_err(npz_bytes(joints=rec.joints, frames=rec.frames[:-2]), "rec.npz")
    assert msg == (
        "rec.npz: joints have 30 steps but frames have 28; there must be one frame per joint sample"
    )


def test_npz_joints_of_wrong_shape() -> None:
    rec = make_recording()
    msg = read_err(npz_bytes(joints=rec.joints[:, :4], frames=rec.frames), "rec.npz")
    assert msg.startswith("rec.npz: joints must have shape T x 5 (RShoulderPitch,")


def test_npz_infinite_angle() -> None:
    rec = make_recording()
    joints = rec.joints.copy()
    joints[7, 2] = np.inf
    msg = read_err(npz_bytes(joints=joints, frames=rec.frames), "rec.npz")
    assert msg == f"rec.npz: joints[7, 2] ({JOINT_NAMES[2]}) is inf, not a finite number"


def test_npz_at_another_rate_is_resampled() -> None:
    rec = make_recording(steps=60)
    back = read_recording(npz_bytes(joints=rec.joints, frames=rec.frames, fps=40.0), "rec.npz")
    assert back.steps == 30  # 0 .. 1.475 s at 40 Hz -> 0 .. 1.45 s at 20 Hz
    np.testing.assert_array_equal(back.joints, rec.joints[::2])
    np.testing.assert_array_equal(back.frames, rec.frames[::2])


def test_oversized_file_on_disk_is_refused_before_reading(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import data.recording.read as recording

    monkeypatch.setattr(recording, "MAX_UPLOAD_BYTES", 1000)
    path = tmp_path / "big.zip"
    path.write_bytes(bytes(5000))
    with pytest.raises(RecordingError, match=r"^big.zip is 0 MB; recordings are limited to 0 MB"):
        read_recording(path, "big.zip")
