"""Crafted recordings (issue 14): each is refused with a message naming the problem, or read as
stored, and the bounds are checked before the work (rows while streaming, headers before decoding)."""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "server"))

import hostile_cases as hostile  # noqa: E402

from data.recording import MAX_JOINT_ROWS, Recording, RecordingError, read_recording, write_zip  # noqa: E402
from data.recording.joints import parse_joints_csv  # noqa: E402


def refused(case: hostile.Case) -> str:
    with pytest.raises(RecordingError) as info:
        read_recording(case.data, case.filename)
    return str(info.value)


def test_a_cell_over_the_csv_field_limit_is_a_line_too_long() -> None:
    assert refused(hostile.csv_cell_over_field_limit()).startswith(
        "joints.csv line 3 is longer than 4096 bytes"
    )


def test_an_unterminated_quote_is_a_csv_error_with_its_line() -> None:
    raw = (hostile.HEADER + '\n0,"' + "1234567890\n" * 20_000).encode()  # a quote never closed
    with pytest.raises(RecordingError, match=r"^joints.csv line \d+ cannot be read as CSV \(field larger"):
        parse_joints_csv(raw)


def test_time_stamps_of_1_7e308_are_too_long_not_an_overflow() -> None:
    assert refused(hostile.time_stamps_1_7e308()) == (
        "the recording is too long: its time stamps run from -1.7e+308 s to 1.7e+308 s; "
        "at most 30 s (600 steps) is accepted"
    )


def test_npz_fps_of_5e_324_is_out_of_range() -> None:
    assert refused(hostile.npz_fps_5e_324()) == (
        "fps.npz: fps must be from 0.01 to 10000 frames per second, got 5e-324"
    )


def test_npz_fps_as_a_one_element_array_is_one_number() -> None:
    case = hostile.npz_fps_one_element_array()
    assert read_recording(case.data, case.filename).steps == 30


def test_npz_utterance_of_undecodable_bytes_is_refused() -> None:
    assert refused(hostile.npz_undecodable_utterance()).startswith(
        "utt.npz: utterance is bytes that are not UTF-8 text; store it as a str"
    )


def test_deeply_nested_meta_json_is_refused_without_recursing() -> None:
    assert refused(hostile.deeply_nested_meta()) == (
        "meta.json is nested too deeply; it must be a flat JSON object"
    )


def test_a_large_meta_json_is_refused_before_parsing() -> None:
    members = hostile.recording_members() | {"meta.json": b"[" * 100_000}
    assert refused(hostile.Case("", "big.zip", hostile.zip_of(members))).startswith(
        "meta.json is 100000 bytes; at most 64 KiB are accepted"
    )


def test_an_exif_rotated_jpeg_beside_a_plain_one_is_read_as_stored() -> None:
    case = hostile.exif_rotated_jpeg()
    rec = read_recording(case.data, case.filename)
    assert rec.frames.shape == (30, 48, 64, 3)


def test_an_encrypted_member_is_refused_by_name() -> None:
    assert refused(hostile.encrypted_member()) == (
        "encrypted.zip: member 'joints.csv' is encrypted (password-protected); "
        "save the recording as a plain zip without a password"
    )


def test_an_npy_header_declaring_10e13_elements_is_refused_before_allocating() -> None:
    msg = refused(hostile.npy_header_10e13_elements())
    assert msg.startswith(
        "corrupt archive: array 'frames' in huge.npz declares shape (1085069444, 48, 64, 3)"
    )
    assert msg.endswith("but its member holds only 1152 bytes")


def test_a_frame_name_of_5000_digits_sorts_as_a_number() -> None:
    case = hostile.frame_name_of_5000_digits()
    assert read_recording(case.data, case.filename).frames.shape == (30, 48, 64, 3)


def test_npz_of_two_1080p_frames_at_fps_1_29_is_refused_before_resampling() -> None:
    assert refused(hostile.npz_1080p_fps_1_29()) == (
        "581 frames of 1920x1080 would take 3447 MB decoded; the limit is 527 MB: "
        "use smaller frames (320x240 is what the corpus uses)"
    )


def test_a_3_5m_row_joints_csv_is_refused_after_the_row_limit() -> None:
    msg = refused(hostile.csv_3_5m_rows())
    assert msg == (
        f"joints.csv has more than {MAX_JOINT_ROWS} rows; "
        "resample it to at most 2000 Hz (the model reads 20 Hz)"
    )


def test_rows_are_counted_while_streaming(monkeypatch: pytest.MonkeyPatch) -> None:
    """The reader stops at the row limit: a stream that raises after it is never read that far."""
    monkeypatch.setattr("data.recording.joints.MAX_JOINT_ROWS", 10)

    class Endless:
        def __init__(self) -> None:
            self.lines = 0

        def readline(self, limit: int) -> bytes:
            self.lines += 1
            return (hostile.HEADER if self.lines == 1 else f"{self.lines},0,0,0,0.5,0").encode() + b"\n"

    stream = Endless()
    with pytest.raises(RecordingError, match="more than 10 rows"):
        parse_joints_csv(stream)  # type: ignore[arg-type]
    assert stream.lines == 12


REAL_CAPTURE = cv2.VideoCapture


class CountingCapture:
    """cv2.VideoCapture, counting the frames grabbed and the captures opened."""

    opened = 0
    grabs = 0

    def __init__(self, path: str) -> None:
        CountingCapture.opened += 1
        self.cap = REAL_CAPTURE(path)

    def grab(self) -> bool:
        CountingCapture.grabs += 1
        return self.cap.grab()

    def __getattr__(self, name: str) -> object:
        return getattr(self.cap, name)


def mp4_recording(tmp_path: Path, steps: int, width: int, height: int) -> bytes:
    frames = np.stack([hostile.frame(width, height)] * steps)
    rec = Recording(hostile.joints(steps), frames, 20.0, None)
    return write_zip(rec, tmp_path / "rec.zip", frames_as="mp4").read_bytes()


def test_a_video_is_decoded_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    data = mp4_recording(tmp_path, 30, 64, 48)
    monkeypatch.setattr(cv2, "VideoCapture", CountingCapture)
    CountingCapture.opened = CountingCapture.grabs = 0
    assert read_recording(data, "rec.zip").frames.shape == (30, 48, 64, 3)
    assert CountingCapture.opened == 1 and CountingCapture.grabs == 30


def test_a_video_too_big_decoded_is_refused_from_its_header(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    data = mp4_recording(tmp_path, 30, 1920, 1080)
    monkeypatch.setattr("data.recording.frames.MAX_FRAME_BYTES", 10 * 1920 * 1080 * 3)
    monkeypatch.setattr(cv2, "VideoCapture", CountingCapture)
    CountingCapture.grabs = 0
    with pytest.raises(RecordingError, match=r"^30 frames of 1920x1080 would take 178 MB decoded"):
        read_recording(data, "rec.zip")
    assert CountingCapture.grabs == 0
