"""Camera frames on the 20 Hz grid: the source frame nearest to each step, the decoded-size check,
and the video reader (frames counted before any is kept)."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np

from data.recording.format import MAX_FRAME_BYTES, RecordingError, check_size
from data.world import FPS


def frame_times(count: int, t0: float, t1: float, fps: float | None) -> np.ndarray:
    """Time of each source frame: at `fps` from t0 when given, else spread evenly over [t0, t1]."""
    if fps is not None:
        return t0 + np.arange(count) / fps
    if count == 1:
        return np.array([t0])
    return np.linspace(t0, t1, count)


def nearest_frames(grid: np.ndarray, frame_times: np.ndarray, what: str, span: float) -> np.ndarray:
    """Index of the source frame nearest to each grid time."""
    covered = frame_times[-1] - frame_times[0]
    if len(frame_times) > 1 and covered < 0.9 * span - 1.0 / FPS:
        raise RecordingError(
            f"{what}: the frames cover {covered:.2f} s but the joints cover {span:.2f} s; "
            "fix meta.json fps or supply frames for the whole recording"
        )
    idx = np.searchsorted(frame_times, grid)
    idx = np.clip(idx, 1, len(frame_times) - 1) if len(frame_times) > 1 else np.zeros_like(idx)
    if len(frame_times) > 1:
        left = frame_times[idx - 1]
        idx = np.where(np.abs(grid - left) <= np.abs(frame_times[idx] - grid), idx - 1, idx)
    return idx


def check_memory(steps: int, width: int, height: int) -> None:
    need = steps * width * height * 3
    if need > MAX_FRAME_BYTES:
        raise RecordingError(
            f"{steps} frames of {width}x{height} would take {need / 1024**2:.0f} MB decoded; the limit is "
            f"{MAX_FRAME_BYTES / 1024**2:.0f} MB: use smaller frames (320x240 is what the corpus uses)"
        )


@contextlib.contextmanager
def _video_capture(data: bytes, suffix: str) -> Iterator[cv2.VideoCapture]:
    """cv2.VideoCapture reads files only: spill the bytes to a temporary file."""
    fd, tmp = tempfile.mkstemp(suffix=suffix)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        cap = cv2.VideoCapture(tmp)
        try:
            yield cap
        finally:
            cap.release()
    finally:
        os.unlink(tmp)


def read_video(
    data: bytes, member: str, grid: np.ndarray, times: np.ndarray, fps: float | None
) -> np.ndarray:
    undecodable = (
        f"{member} has no decodable frames (corrupt file, or a codec OpenCV cannot read: "
        "use mp4v or MJPG, or frames/*.png)"
    )
    suffix = Path(member).suffix
    # Pass 1 counts the frames that really decode (the container's frame count is not trusted).
    with _video_capture(data, suffix) as cap:
        if not cap.isOpened():
            raise RecordingError(undecodable)
        width = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        height = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        claimed = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        count = 0
        while count <= 100_000 and cap.grab():
            count += 1
    if count == 0:
        raise RecordingError(undecodable)
    if claimed > 0 and count < claimed // 2:
        raise RecordingError(f"{member} is truncated or corrupt: only {count} of its {claimed} frames decode")
    check_size(width, height, member)
    check_memory(len(grid), width, height)
    picks = nearest_frames(grid, frame_times(count, times[0], times[-1], fps), member, times[-1] - times[0])
    wanted = set(picks.tolist())
    decoded: dict[int, np.ndarray] = {}
    with _video_capture(data, suffix) as cap:
        for i in range(count):
            if not cap.grab():
                break
            if i in wanted:
                ok, bgr = cap.retrieve()
                if not ok or bgr is None:
                    break
                decoded[i] = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    if len(decoded) < len(wanted):
        raise RecordingError(
            f"{member} is corrupt: only {len(decoded)} of the {len(wanted)} needed frames decode"
        )
    return np.stack([decoded[i] for i in picks.tolist()])
