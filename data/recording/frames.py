"""Camera frames on the 20 Hz grid: the source frame nearest to each step, the decoded-size check,
and the two readers (images, video), which check sizes from headers and decode each picked frame
once into one preallocated array."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import cv2
import numpy as np
from PIL import Image

from data.recording.archive import open_member, read_member
from data.recording.format import MAX_FRAME_BYTES, MAX_VIDEO_FRAMES, RecordingError, check_size
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


def _fill(out: np.ndarray, positions: np.ndarray, rgb: np.ndarray, what: str) -> None:
    """Put one decoded frame at the grid steps that take it, if it has the size its header said."""
    if rgb.shape != out.shape[1:]:
        raise RecordingError(
            f"{what} decodes to {rgb.shape[1]}x{rgb.shape[0]} but its header says "
            f"{out.shape[2]}x{out.shape[1]}; all frames must have the same size"
        )
    out[positions] = rgb


def steps_of(picks: np.ndarray) -> dict[int, np.ndarray]:
    """Source frame -> the grid steps that take it."""
    frames, inverse = np.unique(picks, return_inverse=True)
    return {int(f): np.flatnonzero(inverse == k) for k, f in enumerate(frames)}


# ---------------------------------------------------------------------------------------------- images


def _image_size(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str) -> tuple[int, int]:
    """Width and height from the image's header (PIL reads the header only)."""
    with open_member(archive, info, name) as stream:
        try:
            with Image.open(stream) as image:
                return image.size
        except (OSError, Image.DecompressionBombError, ValueError, SyntaxError):
            raise RecordingError(f"{info.filename} is not a decodable PNG/JPEG image") from None


def read_images(
    archive: zipfile.ZipFile,
    infos: list[zipfile.ZipInfo],
    name: str,
    grid: np.ndarray,
    times: np.ndarray,
    fps: float | None,
) -> np.ndarray:
    """frames/*.png|jpg on the grid: every header read and checked first, then only the picked
    images decoded, each once, into the one output array. EXIF orientation is ignored: a frame is
    used as stored."""
    size: tuple[int, int] | None = None
    for info in infos:
        this = _image_size(archive, info, name)
        if size is None:
            check_size(*this, info.filename)
            check_memory(len(grid), *this)
            size = this
        elif this != size:
            raise RecordingError(
                f"{info.filename} is {this[0]}x{this[1]} but the first frame is {size[0]}x{size[1]}; "
                "all frames must have the same size"
            )
    assert size is not None
    picks = nearest_frames(
        grid, frame_times(len(infos), times[0], times[-1], fps), "frames/", times[-1] - times[0]
    )
    out = np.empty((len(grid), size[1], size[0], 3), np.uint8)
    for i, positions in steps_of(picks).items():
        blob = np.frombuffer(read_member(archive, infos[i], name), np.uint8)
        bgr = cv2.imdecode(blob, cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION)
        if bgr is None:
            raise RecordingError(f"{infos[i].filename} cannot be decoded as an image")
        _fill(out, positions, cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), infos[i].filename)
    return out


# ----------------------------------------------------------------------------------------------- video


@contextlib.contextmanager
def _video_capture(stream: IO[bytes], suffix: str) -> Iterator[cv2.VideoCapture]:
    """cv2.VideoCapture reads files only: spill the member to a temporary file as it decompresses."""
    fd, tmp = tempfile.mkstemp(suffix=suffix)
    try:
        with os.fdopen(fd, "wb") as fh:
            shutil.copyfileobj(stream, fh, 1 << 20)
        cap = cv2.VideoCapture(tmp)
        try:
            yield cap
        finally:
            cap.release()
    finally:
        os.unlink(tmp)


def read_video(
    stream: IO[bytes], member: str, grid: np.ndarray, times: np.ndarray, fps: float | None
) -> np.ndarray:
    """A video's frames on the grid: counted and sized from the container's header, checked, then
    decoded once up to the last frame needed."""
    undecodable = (
        f"{member} has no decodable frames (corrupt file, or a codec OpenCV cannot read: "
        "use mp4v or MJPG, or frames/*.png)"
    )
    with _video_capture(stream, Path(member).suffix) as cap:
        claimed = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) if cap.isOpened() else 0
        if claimed <= 0:
            raise RecordingError(undecodable)
        if claimed > MAX_VIDEO_FRAMES:
            raise RecordingError(
                f"{member} holds {claimed} frames; at most {MAX_VIDEO_FRAMES} are accepted "
                "(the model reads 20 per second: re-encode it at a lower frame rate)"
            )
        width, height = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        check_size(width, height, member)
        check_memory(len(grid), width, height)
        picks = nearest_frames(
            grid, frame_times(claimed, times[0], times[-1], fps), member, times[-1] - times[0]
        )
        out = np.empty((len(grid), height, width, 3), np.uint8)
        decoded = _decode_picked(cap, steps_of(picks), out, member)
    if decoded == 0:
        raise RecordingError(undecodable)
    if decoded <= int(picks.max()):
        raise RecordingError(
            f"{member} is truncated or corrupt: only {decoded} of its {claimed} frames decode"
        )
    return out


def _decode_picked(cap: cv2.VideoCapture, steps: dict[int, np.ndarray], out: np.ndarray, member: str) -> int:
    """Grab every frame up to the last one needed, keep the picked ones; how many decoded."""
    for i in range(max(steps) + 1):
        if not cap.grab():
            return i
        if i in steps:
            ok, bgr = cap.retrieve()
            if not ok or bgr is None:
                return i
            _fill(out, steps[i], cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), f"{member} frame {i}")
    return max(steps) + 1
