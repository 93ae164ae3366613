"""Recording format v1: one robot interaction as joint angles, camera frames and an optional utterance.

A recording is either

- a ``.zip`` holding ``joints.csv`` (header ``t,RShoulderPitch,RShoulderRoll,RElbowYaw,RElbowRoll,
  RWristYaw``; seconds and radians, any rate), camera frames as ``video.mp4`` / ``video.avi`` or as
  ``frames/*.png|jpg`` and an optional ``meta.json`` (``{"utterance": "...", "fps": 20}``), or
- a ``.npz`` holding ``joints`` (T x 5 float, radians), ``frames`` (T x H x W x 3 uint8 RGB) and
  optionally ``fps`` and ``utterance``.

`read_recording` turns either into a `Recording` on the model's 20 Hz grid (joints by linear
interpolation, frames by nearest frame) or raises `RecordingError` with a message that names the
problem. `write_zip` and `write_npz` write the format atomically. The full description, with the

The package: `format` (the dataclass, the error, the limits), `read` (the zip layout, and which
layout a file is), `archive` (the zip container: member checks, reading), `npz` (the npz layout),
`joints` (joints.csv and the 20 Hz grid), `frames` (images and video), `write`.
"""

from data.recording.format import (
    BOMB_MIN_MEMBER_BYTES,
    CSV_HEADER,
    FORMAT_VERSION,
    IMAGE_SUFFIXES,
    LIMIT_TOLERANCE,
    MAX_COMPRESSION_RATIO,
    MAX_CSV_LINE_BYTES,
    MAX_FPS,
    MAX_FRAME_BYTES,
    MAX_HEIGHT,
    MAX_JOINT_ROWS,
    MAX_MEMBERS,
    MAX_META_BYTES,
    MAX_STEPS,
    MAX_UNCOMPRESSED_BYTES,
    MAX_UPLOAD_BYTES,
    MAX_UTTERANCE_CHARS,
    MAX_VIDEO_FRAMES,
    MAX_WIDTH,
    MIN_FPS,
    MIN_SIDE,
    MIN_STEPS,
    VIDEO_NAMES,
    Recording,
    RecordingError,
)
from data.recording.read import read_recording
from data.recording.write import add_zip_member, atomic_write, joints_csv, write_npz, write_zip
from data.world import FPS

__all__ = [
    "BOMB_MIN_MEMBER_BYTES",
    "CSV_HEADER",
    "FORMAT_VERSION",
    "FPS",
    "IMAGE_SUFFIXES",
    "LIMIT_TOLERANCE",
    "MAX_COMPRESSION_RATIO",
    "MAX_CSV_LINE_BYTES",
    "MAX_FPS",
    "MAX_FRAME_BYTES",
    "MAX_HEIGHT",
    "MAX_JOINT_ROWS",
    "MAX_MEMBERS",
    "MAX_META_BYTES",
    "MAX_STEPS",
    "MAX_UNCOMPRESSED_BYTES",
    "MAX_UPLOAD_BYTES",
    "MAX_UTTERANCE_CHARS",
    "MAX_VIDEO_FRAMES",
    "MAX_WIDTH",
    "MIN_FPS",
    "MIN_SIDE",
    "MIN_STEPS",
    "VIDEO_NAMES",
    "Recording",
    "RecordingError",
    "add_zip_member",
    "atomic_write",
    "joints_csv",
    "read_recording",
    "write_npz",
    "write_zip",
]
