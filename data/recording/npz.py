"""The npz layout: arrays ``joints``, ``frames`` and optionally ``fps``, ``utterance``.

Each array's .npy header is read and checked (dtype, shape, declared size against the member's
size) before its data is read, pickles are never loaded, and the frames are streamed one by one
into the 20 Hz grid's array, so that neither a lying header nor a resampling to many more steps
allocates more than the limits allow.
"""

from __future__ import annotations

import math
import zipfile
from dataclasses import dataclass
from typing import IO

import numpy as np

from data.nao import JOINT_NAMES
from data.recording.archive import open_member
from data.recording.format import (
    MAX_UTTERANCE_CHARS,
    Recording,
    RecordingError,
    check_fps,
    check_frame_shape,
    check_utterance,
)
from data.recording.frames import check_memory, nearest_frames, steps_of
from data.recording.joints import check_limits, resample_joints, time_grid
from data.world import FPS

KEYS = ("joints", "frames", "fps", "utterance")
MAX_SMALL_ARRAY_BYTES = 4 * MAX_UTTERANCE_CHARS + 64  # fps and utterance
MAX_HEADER_BYTES = 10_000  # numpy's own default


@dataclass(frozen=True)
class Member:
    """One array of the archive, as its .npy header describes it."""

    key: str
    info: zipfile.ZipInfo
    shape: tuple[int, ...]
    fortran: bool
    dtype: np.dtype


def is_npz(infos: list[zipfile.ZipInfo]) -> bool:
    names = [i.filename for i in infos]
    return any(n.endswith(".npy") for n in names) and not any(n.endswith("joints.csv") for n in names)


def read_npz(archive: zipfile.ZipFile, infos: list[zipfile.ZipInfo], name: str) -> Recording:
    members = _members(archive, infos, name)
    joints_m, frames_m = members["joints"], members["frames"]
    _check_joints_header(joints_m, name)
    check_frame_shape(frames_m.shape, frames_m.dtype, f"{name}: frames")
    if frames_m.shape[0] != joints_m.shape[0]:
        raise RecordingError(
            f"{name}: joints have {joints_m.shape[0]} steps but frames have {frames_m.shape[0]}; "
            "there must be one frame per joint sample"
        )
    fps = _fps(_load(archive, members["fps"], name), name) if "fps" in members else FPS
    utterance = None
    if "utterance" in members:
        utterance = _utterance(_load(archive, members["utterance"], name), name)
    joints = _finite_joints(_load(archive, joints_m, name), name)
    times = np.arange(len(joints)) / fps
    joints = check_limits(joints, lambda i: f"step {i} (t = {times[i]:g} s)")
    grid = time_grid(0.0, times[-1] if len(times) else 0.0)
    check_memory(len(grid), frames_m.shape[2], frames_m.shape[1])
    picks = nearest_frames(grid, times, name, times[-1]) if fps != FPS else np.arange(len(grid))
    if fps != FPS:
        joints = resample_joints(times, joints, grid)
    frames = _frames_on_grid(archive, frames_m, picks, name)
    return Recording(joints=joints, frames=frames, fps=FPS, utterance=utterance)


def _members(archive: zipfile.ZipFile, infos: list[zipfile.ZipInfo], name: str) -> dict[str, Member]:
    by_key = {i.filename[: -len(".npy")]: i for i in infos if i.filename.endswith(".npy")}
    for key in ("joints", "frames"):
        if key not in by_key:
            raise RecordingError(
                f"{name} has no {key!r} array (it holds: {', '.join(by_key) or 'nothing'}); "
                "a .npz recording needs joints (T x 5) and frames (T x H x W x 3)"
            )
    return {key: _header(archive, by_key[key], key, name) for key in KEYS if key in by_key}


def _header(archive: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, name: str) -> Member:
    """The .npy header of one member, checked before any of its data is read."""
    with open_member(archive, info, name) as stream:
        try:
            version = np.lib.format.read_magic(stream)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(stream, MAX_HEADER_BYTES)
            elif version == (2, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(stream, MAX_HEADER_BYTES)
            else:
                raise ValueError(f"unsupported .npy format version {version}")
        except ValueError as exc:
            raise RecordingError(f"corrupt archive: array {key!r} in {name} cannot be read ({exc})") from None
    if dtype.hasobject:
        raise RecordingError(
            f"{name}: array {key!r} holds Python objects (a pickle), which are never loaded for safety; "
            "store numbers as numeric arrays and text as a plain string (np.savez(..., utterance='...'))"
        )
    declared = math.prod(shape) * dtype.itemsize
    if declared > info.file_size:
        raise RecordingError(
            f"corrupt archive: array {key!r} in {name} declares shape {shape} ({declared} bytes) "
            f"but its member holds only {info.file_size} bytes"
        )
    if key in ("fps", "utterance") and declared > MAX_SMALL_ARRAY_BYTES:
        raise RecordingError(f"{name}: {key} must be a single value, got an array of shape {shape}")
    return Member(key, info, tuple(shape), fortran, dtype)


def _read_header(stream: IO[bytes], key: str, name: str) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, fortran_order, dtype) from the start of a .npy stream, which is left at the data."""
    try:
        version = np.lib.format.read_magic(stream)
        if version == (1, 0):
            return np.lib.format.read_array_header_1_0(stream, MAX_HEADER_BYTES)
        if version == (2, 0):
            return np.lib.format.read_array_header_2_0(stream, MAX_HEADER_BYTES)
        raise ValueError(f"unsupported .npy format version {version}")
    except ValueError as exc:
        raise RecordingError(f"corrupt archive: array {key!r} in {name} cannot be read ({exc})") from None


def _load(archive: zipfile.ZipFile, member: Member, name: str) -> np.ndarray:
    """A whole (header-checked) array."""
    with open_member(archive, member.info, name) as stream:
        try:
            return np.lib.format.read_array(stream, allow_pickle=False, max_header_size=MAX_HEADER_BYTES)
        except ValueError as exc:
            raise RecordingError(
                f"corrupt archive: array {member.key!r} in {name} cannot be read ({exc})"
            ) from None


def _frames_on_grid(archive: zipfile.ZipFile, member: Member, picks: np.ndarray, name: str) -> np.ndarray:
    """frames[picks], read one source frame at a time (a Fortran-ordered array is read whole)."""
    if member.fortran:
        return np.ascontiguousarray(_load(archive, member, name)[picks])
    height, width = member.shape[1:3]
    size = height * width * 3
    out = np.empty((len(picks), height, width, 3), np.uint8)
    steps = steps_of(picks)
    with open_member(archive, member.info, name) as stream:
        _read_header(stream, "frames", name)
        for i in range(max(steps) + 1):
            raw = stream.read(size)
            if len(raw) < size:
                raise RecordingError(f"corrupt archive: array 'frames' in {name} ends after {i} frames")
            if i in steps:
                out[steps[i]] = np.frombuffer(raw, np.uint8).reshape(height, width, 3)
    return out


def _check_joints_header(member: Member, name: str) -> None:
    if member.dtype.kind not in "fiu":
        raise RecordingError(f"{name}: joints must be numbers (float radians), got dtype {member.dtype}")
    if len(member.shape) != 2 or member.shape[1] != len(JOINT_NAMES):
        raise RecordingError(
            f"{name}: joints must have shape T x {len(JOINT_NAMES)} ({', '.join(JOINT_NAMES)}), "
            f"got {member.shape}"
        )


def _finite_joints(joints: np.ndarray, name: str) -> np.ndarray:
    """The joints array as T x 5 finite float64 radians."""
    joints = joints.astype(np.float64)
    if not np.all(np.isfinite(joints)):
        i, j = np.argwhere(~np.isfinite(joints))[0]
        raise RecordingError(
            f"{name}: joints[{i}, {j}] ({JOINT_NAMES[j]}) is {joints[i, j]}, not a finite number"
        )
    return joints


def _fps(value: np.ndarray, name: str) -> float:
    """One number (a scalar or a one-element array) in the accepted range."""
    if value.size != 1 or value.dtype.kind not in "fiu":
        raise RecordingError(f"{name}: fps must be one positive number, got {value!r}")
    return check_fps(float(value.reshape(())), name)


def _utterance(value: np.ndarray, name: str) -> str:
    if value.dtype.kind not in "US" or value.size != 1:
        raise RecordingError(
            f"{name}: utterance must be a single string, got an array of dtype {value.dtype}"
        )
    text = value.reshape(()).item()
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:
            raise RecordingError(
                f"{name}: utterance is bytes that are not UTF-8 text; store it as a str "
                "(np.savez(..., utterance='push the red apple.'))"
            ) from None
    return check_utterance(text, name)
