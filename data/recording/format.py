"""Format v1 itself: the `Recording` a reader returns, `RecordingError`, and the limits a file must keep.

The limits guard the upload path against hostile input (sizes, member counts, compression ratios
are checked before anything is decompressed or decoded); ``docs/recording-format.md`` lists them
with every error message.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from data.nao import JOINT_NAMES
from data.world import FPS

FORMAT_VERSION = 1
CSV_HEADER: tuple[str, ...] = ("t", *JOINT_NAMES)

MAX_UPLOAD_BYTES = 100 * 1024**2  # size of the .zip / .npz file itself
MAX_UNCOMPRESSED_BYTES = 400 * 1024**2  # sum of the archive members' uncompressed sizes
MAX_COMPRESSION_RATIO = 500  # for members larger than BOMB_MIN_MEMBER_BYTES (deflate tops out ~1030)
BOMB_MIN_MEMBER_BYTES = 50 * 1024**2
MAX_MEMBERS = 5000
MIN_STEPS = 20  # 1 s at 20 Hz
MAX_STEPS = 600  # 30 s at 20 Hz
MAX_FRAME_BYTES = MAX_STEPS * 640 * 480 * 3  # decoded frames on the 20 Hz grid: 30 s of 640 x 480 (527 MiB)
MAX_JOINT_ROWS = 60_000  # rows of joints.csv (30 s at 2 kHz), counted while reading
MAX_CSV_LINE_BYTES = 4096  # one row of joints.csv (six numbers need ~150)
MAX_META_BYTES = 64 * 1024  # meta.json
MAX_VIDEO_FRAMES = 20 * MAX_STEPS  # frames a video may hold (30 s at 400 fps), from its header
MIN_FPS, MAX_FPS = 0.01, 10_000.0  # a rate given in meta.json or the .npz
MIN_SIDE = 32  # pixels
MAX_WIDTH, MAX_HEIGHT = 1920, 1080  # either orientation
LIMIT_TOLERANCE = 0.02  # rad; angles this close outside a limit are clipped to it
MAX_UTTERANCE_CHARS = 500

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
VIDEO_NAMES = ("video.mp4", "video.avi")


class RecordingError(ValueError):
    """A recording that cannot be read; the message says what is wrong and how to fix it."""


@dataclass
class Recording:
    """Joint angles and RGB camera frames on one time grid (20 Hz after `read_recording`)."""

    joints: np.ndarray  # [T, 5] float64, radians, order JOINT_NAMES
    frames: np.ndarray  # [T, H, W, 3] uint8 RGB
    fps: float = FPS
    utterance: str | None = None

    def __post_init__(self) -> None:
        self.joints = np.asarray(self.joints, dtype=np.float64)
        if self.joints.ndim != 2 or self.joints.shape[1] != len(JOINT_NAMES):
            raise RecordingError(f"joints must be T x {len(JOINT_NAMES)}, got shape {self.joints.shape}")
        check_frame_array(self.frames, "frames")
        if len(self.frames) != len(self.joints):
            raise RecordingError(
                f"joints have {len(self.joints)} steps but frames have {len(self.frames)}; "
                "there must be one frame per joint sample"
            )
        if not (math.isfinite(self.fps) and self.fps > 0):
            raise RecordingError(f"fps must be a positive number, got {self.fps}")

    @property
    def steps(self) -> int:
        return len(self.joints)

    @property
    def duration(self) -> float:
        """Seconds covered by the samples."""
        return self.steps / self.fps


def check_frame_array(frames: object, what: str) -> None:
    if not isinstance(frames, np.ndarray):
        raise RecordingError(f"{what} must be a numpy array, got {type(frames).__name__}")
    check_frame_shape(frames.shape, frames.dtype, what)


def check_frame_shape(shape: tuple[int, ...], dtype: np.dtype, what: str) -> None:
    """Frames of this shape and dtype are T x H x W x 3 uint8 of an accepted size (checked from an
    array's header, before its data is read)."""
    if dtype != np.uint8:
        raise RecordingError(
            f"{what} must be uint8 RGB (0..255), got dtype {dtype}; convert with "
            "(frames * 255).clip(0, 255).astype(np.uint8) if they are floats in [0, 1]"
        )
    if len(shape) != 4 or shape[3] != 3:
        raise RecordingError(f"{what} must have shape T x H x W x 3 (RGB), got {tuple(shape)}")
    check_size(shape[2], shape[1], what)


def check_fps(fps: object, where: str) -> float:
    """A frame rate as a float in [MIN_FPS, MAX_FPS]."""
    if isinstance(fps, bool) or not isinstance(fps, int | float) or not math.isfinite(fps) or fps <= 0:
        raise RecordingError(f"{where}: fps must be a positive number, got {fps!r}")
    if not MIN_FPS <= fps <= MAX_FPS:
        raise RecordingError(
            f"{where}: fps must be from {MIN_FPS:g} to {MAX_FPS:g} frames per second, got {fps!r}"
        )
    return float(fps)


def check_size(width: int, height: int, what: str) -> None:
    if min(width, height) < MIN_SIDE:
        raise RecordingError(
            f"{what} is {width}x{height} pixels; frames must be at least {MIN_SIDE} pixels a side"
        )
    if max(width, height) > MAX_WIDTH or min(width, height) > MAX_HEIGHT:
        raise RecordingError(
            f"{what} is {width}x{height} pixels; frames may be at most {MAX_WIDTH}x{MAX_HEIGHT} "
            "(320x240 is what the corpus uses)"
        )


def check_utterance(value: object, where: str) -> str:
    """The utterance a teacher said, as given in meta.json or the .npz: a string, not too long."""
    if not isinstance(value, str):
        raise RecordingError(f"{where}: utterance must be a string, got {type(value).__name__} {value!r}")
    if len(value) > MAX_UTTERANCE_CHARS:
        raise RecordingError(f"{where}: utterance has {len(value)} characters; at most {MAX_UTTERANCE_CHARS}")
    return value.strip()
