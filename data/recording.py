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
limits and every error message, is in ``docs/recording-format.md``.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import re
import tempfile
import zipfile
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import cv2
import numpy as np
from PIL import Image

from data.nao import JOINT_LIMITS, JOINT_NAMES
from data.world import FPS

FORMAT_VERSION = 1
CSV_HEADER: tuple[str, ...] = ("t", *JOINT_NAMES)

MAX_UPLOAD_BYTES = 100 * 1024**2  # size of the .zip / .npz file itself
MAX_UNCOMPRESSED_BYTES = 400 * 1024**2  # sum of the archive members' uncompressed sizes
MAX_COMPRESSION_RATIO = 500  # for members larger than BOMB_MIN_MEMBER_BYTES (deflate tops out ~1030)
BOMB_MIN_MEMBER_BYTES = 50 * 1024**2
MAX_MEMBERS = 5000
MAX_FRAME_BYTES = 1024**3  # decoded frames on the 20 Hz grid
MIN_STEPS = 20  # 1 s at 20 Hz
MAX_STEPS = 600  # 30 s at 20 Hz
MIN_SIDE = 32  # pixels
MAX_WIDTH, MAX_HEIGHT = 1920, 1080  # either orientation
LIMIT_TOLERANCE = 0.02  # rad; angles this close outside a limit are clipped to it
MAX_UTTERANCE_CHARS = 500

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
VIDEO_NAMES = ("video.mp4", "video.avi")
_IGNORED = re.compile(r"(^|/)(__MACOSX/|\.DS_Store$|Thumbs\.db$)")
_FIXED_DATE = (1980, 1, 1, 0, 0, 0)


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
        _check_frame_array(self.frames, "frames")
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


# ----------------------------------------------------------------------------------------------- read


def read_recording(source: bytes | Path, filename: str) -> Recording:
    """Read a format-v1 recording from bytes or a file; `filename` gives the name used in messages.

    The result is on the 20 Hz grid, its joints inside the NAO limits and its frames RGB uint8.
    Raises `RecordingError` naming the problem for anything malformed.
    """
    data = _read_source(source, filename)
    name = filename or "recording"
    if len(data) == 0:
        raise RecordingError(f"{name} is empty (0 bytes)")
    if data.startswith(b"\x93NUMPY"):
        raise RecordingError(
            f"{name} is a single .npy array; a recording needs joints and frames together: "
            "save them with np.savez(path, joints=..., frames=...)"
        )
    if not data.startswith((b"PK\x03\x04", b"PK\x05\x06")):
        if Path(name).suffix.lower() in (".zip", ".npz"):
            raise RecordingError(f"corrupt archive: {name} does not start like a zip/npz file")
        raise RecordingError(
            f"{name} is not a recording: expected a .zip (joints.csv + frames) or a .npz "
            "(joints, frames arrays)"
        )
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError) as exc:
        raise RecordingError(f"corrupt archive: {name} cannot be opened as a zip/npz ({exc})") from exc
    with archive:
        members = _check_members(archive, name)
        if any(m.filename.endswith(".npy") for m in members) and not any(
            m.filename.endswith("joints.csv") for m in members
        ):
            rec = _read_npz(data, name)
        else:
            rec = _read_zip(archive, members, name)
    return rec


def _read_source(source: bytes | Path, filename: str) -> bytes:
    if isinstance(source, bytes | bytearray | memoryview):
        data = bytes(source)
    else:
        path = Path(source)
        if not path.is_file():
            raise RecordingError(f"{path} does not exist or is not a file")
        size = path.stat().st_size
        if size > MAX_UPLOAD_BYTES:
            raise RecordingError(_too_big(filename or path.name, size))
        data = path.read_bytes()
    if len(data) > MAX_UPLOAD_BYTES:
        raise RecordingError(_too_big(filename, len(data)))
    return data


def _too_big(name: str, size: int) -> str:
    return (
        f"{name} is {size / 1024**2:.0f} MB; recordings are limited to {MAX_UPLOAD_BYTES / 1024**2:.0f} MB "
        "(use fewer or smaller frames, or an mp4 video)"
    )


def _check_members(archive: zipfile.ZipFile, name: str) -> list[zipfile.ZipInfo]:
    """Reject unsafe member paths and decompression bombs before anything is decompressed."""
    infos = [i for i in archive.infolist() if not i.is_dir() and not _IGNORED.search(i.filename)]
    if not infos:
        raise RecordingError(f"{name} is an empty archive: it holds no files")
    if len(infos) > MAX_MEMBERS:
        raise RecordingError(f"{name} holds {len(infos)} files; at most {MAX_MEMBERS} are accepted")
    for info in infos:
        member = info.filename.replace("\\", "/")
        if member.startswith("/") or re.match(r"^[A-Za-z]:", member) or ".." in member.split("/"):
            raise RecordingError(
                f"{name} contains the unsafe path {info.filename!r}: member paths must be relative "
                "and must not contain '..'"
            )
    total = sum(i.file_size for i in infos)
    if total > MAX_UNCOMPRESSED_BYTES:
        raise RecordingError(
            f"{name} would unpack to {total / 1024**2:.0f} MB, more than the limit of "
            f"{MAX_UNCOMPRESSED_BYTES / 1024**2:.0f} MB (decompression bomb?)"
        )
    for info in infos:
        ratio = info.file_size / max(info.compress_size, 1)
        if info.file_size > BOMB_MIN_MEMBER_BYTES and ratio > MAX_COMPRESSION_RATIO:
            raise RecordingError(
                f"{name}: member {info.filename!r} expands {ratio:.0f}-fold to "
                f"{info.file_size / 1024**2:.0f} MB (decompression bomb?)"
            )
    return infos


def _read_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str) -> bytes:
    try:
        return archive.read(info)
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError, NotImplementedError) as exc:
        raise RecordingError(f"corrupt archive: {info.filename!r} in {name} cannot be read ({exc})") from exc


# ------------------------------------------------------------------------------------------ zip layout


def _read_zip(archive: zipfile.ZipFile, infos: list[zipfile.ZipInfo], name: str) -> Recording:
    by_name = {i.filename.replace("\\", "/"): i for i in infos}
    prefix = _layout_prefix(by_name, name)
    files = {k[len(prefix) :]: v for k, v in by_name.items() if k.startswith(prefix)}

    times, joints = _parse_joints_csv(_read_member(archive, files["joints.csv"], name))
    meta = _parse_meta(_read_member(archive, files["meta.json"], name)) if "meta.json" in files else {}
    grid = _grid(times[0], times[-1])
    joints = _resample_joints(times, joints, grid)

    videos = [v for v in VIDEO_NAMES if v in files]
    images = sorted(
        (k for k in files if k.startswith("frames/") and k.lower().endswith(IMAGE_SUFFIXES)), key=_natural_key
    )
    if len(videos) > 1 or (videos and images):
        found = ", ".join(videos + (["frames/"] if images else []))
        raise RecordingError(f"{name} holds more than one set of frames ({found}); keep exactly one")
    if videos:
        data = _read_member(archive, files[videos[0]], name)
        frames = _read_video(data, videos[0], grid, times, meta.get("fps"))
    elif images:
        frames = _read_images(archive, [files[k] for k in images], name, grid, times, meta.get("fps"))
    else:
        raise RecordingError(
            f"{name} has no camera frames: add video.mp4 (or video.avi) or images frames/*.png|jpg"
        )
    return Recording(joints=joints, frames=frames, fps=FPS, utterance=meta.get("utterance"))


def _natural_key(name: str) -> list[tuple[int, int | str]]:
    """Name order with numbers compared as numbers: frame2.png before frame10.png."""
    return [(0, int(part)) if part.isdigit() else (1, part) for part in re.split(r"(\d+)", name) if part]


def _layout_prefix(by_name: dict[str, zipfile.ZipInfo], name: str) -> str:
    """'' when joints.csv is at the top, 'folder/' when the archive wraps one folder."""
    if "joints.csv" in by_name:
        return ""
    nested = [k for k in by_name if k.endswith("/joints.csv") and k.count("/") == 1]
    if len(nested) == 1:
        return nested[0][: -len("joints.csv")]
    listing = ", ".join(sorted(by_name)[:5]) + (" ..." if len(by_name) > 5 else "")
    raise RecordingError(f"{name} has no joints.csv at its top level (it holds: {listing})")


def _parse_joints_csv(raw: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Times [N] in seconds and angles [N, 5] in radians (JOINT_NAMES order), validated."""
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RecordingError("joints.csv is not UTF-8 text") from exc
    rows = [r for r in csv.reader(io.StringIO(text)) if any(cell.strip() for cell in r)]
    if not rows:
        raise RecordingError("joints.csv is empty; its first line must be the header " + ",".join(CSV_HEADER))
    header = [c.strip() for c in rows[0]]
    if all(_is_number(c) for c in header):
        raise RecordingError("joints.csv has no header row; its first line must be " + ",".join(CSV_HEADER))
    missing = [c for c in CSV_HEADER if c not in header]
    unknown = [c for c in header if c not in CSV_HEADER]
    if missing or unknown or len(set(header)) != len(header):
        parts = []
        if missing:
            parts.append("missing column(s) " + ", ".join(missing))
        if unknown:
            parts.append("unknown column(s) " + ", ".join(repr(c) for c in unknown))
        if len(set(header)) != len(header):
            parts.append("repeated column(s)")
        raise RecordingError(f"joints.csv has {'; '.join(parts)}; the header must be " + ",".join(CSV_HEADER))
    order = [header.index(c) for c in CSV_HEADER]
    body = rows[1:]
    if not body:
        raise RecordingError("joints.csv has a header but no data rows")
    values = np.empty((len(body), len(CSV_HEADER)), dtype=np.float64)
    for r, row in enumerate(body):
        line = r + 2
        if len(row) != len(header):
            raise RecordingError(f"joints.csv line {line} has {len(row)} values; expected {len(header)}")
        for j, col in enumerate(order):
            cell = row[col].strip()
            try:
                value = float(cell)
            except ValueError:
                raise RecordingError(
                    f"joints.csv line {line}, column {CSV_HEADER[j]}: {cell!r} is not a number"
                ) from None
            if not math.isfinite(value):
                raise RecordingError(
                    f"joints.csv line {line}, column {CSV_HEADER[j]}: {cell!r} is not a finite number"
                )
            values[r, j] = value
    times = values[:, 0]
    steps = np.diff(times)
    if np.any(steps <= 0):
        k = int(np.argmax(steps <= 0))
        raise RecordingError(
            f"joints.csv: time goes from {times[k]:g} s (line {k + 2}) to {times[k + 1]:g} s "
            f"(line {k + 3}); t must be strictly increasing"
        )
    joints = _check_limits(values[:, 1:], lambda i: f"t = {times[i]:g} s (joints.csv line {i + 2})")
    return times, joints


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _parse_meta(raw: bytes) -> dict:
    try:
        meta = json.loads(raw.decode("utf-8-sig"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RecordingError(f"meta.json is not valid JSON ({exc})") from exc
    if not isinstance(meta, dict):
        raise RecordingError(
            f'meta.json must be a JSON object like {{"utterance": ...}}, got {type(meta).__name__}'
        )
    out: dict = {}
    if meta.get("utterance") is not None:
        out["utterance"] = _check_utterance(meta["utterance"], "meta.json")
    if meta.get("fps") is not None:
        fps = meta["fps"]
        if isinstance(fps, bool) or not isinstance(fps, int | float) or not math.isfinite(fps) or fps <= 0:
            raise RecordingError(f"meta.json: fps must be a positive number, got {fps!r}")
        out["fps"] = float(fps)
    return out


def _check_utterance(value: object, where: str) -> str:
    if not isinstance(value, str):
        raise RecordingError(f"{where}: utterance must be a string, got {type(value).__name__} {value!r}")
    if len(value) > MAX_UTTERANCE_CHARS:
        raise RecordingError(f"{where}: utterance has {len(value)} characters; at most {MAX_UTTERANCE_CHARS}")
    return value.strip()


# ------------------------------------------------------------------------------------------- frames


def _frame_times(count: int, t0: float, t1: float, fps: float | None) -> np.ndarray:
    """Time of each source frame: at `fps` from t0 when given, else spread evenly over [t0, t1]."""
    if fps is not None:
        return t0 + np.arange(count) / fps
    if count == 1:
        return np.array([t0])
    return np.linspace(t0, t1, count)


def _nearest_frames(grid: np.ndarray, frame_times: np.ndarray, what: str, span: float) -> np.ndarray:
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


def _check_size(width: int, height: int, what: str) -> None:
    if min(width, height) < MIN_SIDE:
        raise RecordingError(
            f"{what} is {width}x{height} pixels; frames must be at least {MIN_SIDE} pixels a side"
        )
    if max(width, height) > MAX_WIDTH or min(width, height) > MAX_HEIGHT:
        raise RecordingError(
            f"{what} is {width}x{height} pixels; frames may be at most {MAX_WIDTH}x{MAX_HEIGHT} "
            "(320x240 is what the corpus uses)"
        )


def _check_memory(steps: int, width: int, height: int) -> None:
    need = steps * width * height * 3
    if need > MAX_FRAME_BYTES:
        raise RecordingError(
            f"{steps} frames of {width}x{height} would take {need / 1024**2:.0f} MB decoded; the limit is "
            f"{MAX_FRAME_BYTES / 1024**2:.0f} MB: use smaller frames (320x240 is what the corpus uses)"
        )


def _read_images(
    archive: zipfile.ZipFile,
    infos: list[zipfile.ZipInfo],
    name: str,
    grid: np.ndarray,
    times: np.ndarray,
    fps: float | None,
) -> np.ndarray:
    size: tuple[int, int] | None = None
    blobs: list[bytes] = []
    for info in infos:
        blob = _read_member(archive, info, name)
        try:
            with Image.open(io.BytesIO(blob)) as image:  # reads the header only
                this = image.size
        except (OSError, Image.DecompressionBombError, ValueError):
            raise RecordingError(f"{info.filename} is not a decodable PNG/JPEG image") from None
        if size is None:
            _check_size(*this, info.filename)
            _check_memory(len(grid), *this)
            size = this
        elif this != size:
            raise RecordingError(
                f"{info.filename} is {this[0]}x{this[1]} but the first frame is {size[0]}x{size[1]}; "
                "all frames must have the same size"
            )
        blobs.append(blob)
    picks = _nearest_frames(
        grid, _frame_times(len(blobs), times[0], times[-1], fps), "frames/", times[-1] - times[0]
    )
    decoded: dict[int, np.ndarray] = {}
    for i in np.unique(picks):
        bgr = cv2.imdecode(np.frombuffer(blobs[i], np.uint8), cv2.IMREAD_COLOR)
        if bgr is None:
            raise RecordingError(f"{infos[i].filename} cannot be decoded as an image")
        decoded[int(i)] = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    return np.stack([decoded[int(i)] for i in picks])


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


def _read_video(
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
    _check_size(width, height, member)
    _check_memory(len(grid), width, height)
    picks = _nearest_frames(grid, _frame_times(count, times[0], times[-1], fps), member, times[-1] - times[0])
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


def _check_frame_array(frames: object, what: str) -> None:
    if not isinstance(frames, np.ndarray):
        raise RecordingError(f"{what} must be a numpy array, got {type(frames).__name__}")
    if frames.dtype != np.uint8:
        raise RecordingError(
            f"{what} must be uint8 RGB (0..255), got dtype {frames.dtype}; convert with "
            "(frames * 255).clip(0, 255).astype(np.uint8) if they are floats in [0, 1]"
        )
    if frames.ndim != 4 or frames.shape[3] != 3:
        raise RecordingError(f"{what} must have shape T x H x W x 3 (RGB), got {frames.shape}")
    _check_size(frames.shape[2], frames.shape[1], what)


# ---------------------------------------------------------------------------------------- npz layout


def _read_npz(data: bytes, name: str) -> Recording:
    try:
        npz = np.load(io.BytesIO(data), allow_pickle=False)
    except (ValueError, OSError, zipfile.BadZipFile, zlib.error, EOFError) as exc:
        raise RecordingError(f"corrupt archive: {name} cannot be read as .npz ({exc})") from exc
    with npz:
        keys = list(npz.files)
        for key in ("joints", "frames"):
            if key not in keys:
                raise RecordingError(
                    f"{name} has no {key!r} array (it holds: {', '.join(keys) or 'nothing'}); "
                    "a .npz recording needs joints (T x 5) and frames (T x H x W x 3)"
                )
        arrays = {k: _npz_array(npz, k, name) for k in ("joints", "frames", "fps", "utterance") if k in keys}
    joints = arrays["joints"]
    if joints.dtype.kind not in "fiu":
        raise RecordingError(f"{name}: joints must be numbers (float radians), got dtype {joints.dtype}")
    if joints.ndim != 2 or joints.shape[1] != len(JOINT_NAMES):
        raise RecordingError(
            f"{name}: joints must have shape T x {len(JOINT_NAMES)} ({', '.join(JOINT_NAMES)}), "
            f"got {joints.shape}"
        )
    joints = joints.astype(np.float64)
    if not np.all(np.isfinite(joints)):
        i, j = np.argwhere(~np.isfinite(joints))[0]
        raise RecordingError(
            f"{name}: joints[{i}, {j}] ({JOINT_NAMES[j]}) is {joints[i, j]}, not a finite number"
        )
    frames = arrays["frames"]
    _check_frame_array(frames, f"{name}: frames")
    if len(frames) != len(joints):
        raise RecordingError(
            f"{name}: joints have {len(joints)} steps but frames have {len(frames)}; "
            "there must be one frame per joint sample"
        )
    fps = FPS
    if "fps" in arrays:
        value = arrays["fps"]
        if (
            value.size != 1
            or value.dtype.kind not in "fiu"
            or not np.isfinite(value).all()
            or float(value) <= 0
        ):
            raise RecordingError(f"{name}: fps must be one positive number, got {value!r}")
        fps = float(value.reshape(()))
    utterance = None
    if "utterance" in arrays:
        value = arrays["utterance"]
        if value.dtype.kind not in "US" or value.size != 1:
            raise RecordingError(
                f"{name}: utterance must be a single string, got an array of dtype {value.dtype}"
            )
        text = value.reshape(()).item()
        utterance = _check_utterance(text.decode("utf-8") if isinstance(text, bytes) else text, name)
    times = np.arange(len(joints)) / fps
    joints = _check_limits(joints, lambda i: f"step {i} (t = {times[i]:g} s)")
    grid = _grid(0.0, times[-1])
    if fps != FPS:
        joints = _resample_joints(times, joints, grid)
        frames = frames[_nearest_frames(grid, times, name, times[-1])]
    return Recording(joints=joints, frames=np.ascontiguousarray(frames), fps=FPS, utterance=utterance)


def _npz_array(npz: np.lib.npyio.NpzFile, key: str, name: str) -> np.ndarray:
    try:
        return npz[key]
    except ValueError as exc:
        if "allow_pickle" in str(exc):
            raise RecordingError(
                f"{name}: array {key!r} holds Python objects (a pickle), which are never loaded for safety; "
                "store numbers as numeric arrays and text as a plain string (np.savez(..., utterance='...'))"
            ) from None
        raise RecordingError(f"corrupt archive: array {key!r} in {name} cannot be read ({exc})") from exc
    except (OSError, zipfile.BadZipFile, zlib.error, EOFError) as exc:
        raise RecordingError(f"corrupt archive: array {key!r} in {name} cannot be read ({exc})") from exc


# ------------------------------------------------------------------------------------ time and limits


def _grid(t0: float, t1: float) -> np.ndarray:
    """The 20 Hz grid over [t0, t1], with the length checks."""
    steps = int(math.floor((t1 - t0) * FPS + 1e-6)) + 1
    if steps < MIN_STEPS:
        raise RecordingError(
            f"the recording is too short: {t1 - t0:.2f} s ({steps} steps at 20 Hz); "
            f"at least {MIN_STEPS / FPS:g} s ({MIN_STEPS} steps) is needed"
        )
    if steps > MAX_STEPS:
        raise RecordingError(
            f"the recording is too long: {t1 - t0:.2f} s ({steps} steps at 20 Hz); "
            f"at most {MAX_STEPS / FPS:g} s ({MAX_STEPS} steps) is accepted"
        )
    return t0 + np.arange(steps) / FPS


def _resample_joints(times: np.ndarray, joints: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Linear interpolation of each joint onto the 20 Hz grid."""
    return np.stack([np.interp(grid, times, joints[:, j]) for j in range(joints.shape[1])], axis=1)


def _check_limits(joints: np.ndarray, where) -> np.ndarray:
    """Reject angles outside the NAO limits (beyond a small tolerance); clip those within it."""
    low, high = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    bad = (joints < low - LIMIT_TOLERANCE) | (joints > high + LIMIT_TOLERANCE)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        value = joints[i, j]
        hint = (
            " (are the angles in degrees? they must be radians)" if np.abs(joints).max() > 2 * math.pi else ""
        )
        raise RecordingError(
            f"{JOINT_NAMES[j]} = {value:.4f} rad at {where(int(i))} is outside the NAO joint limit "
            f"[{low[j]:.4f}, {high[j]:.4f}] rad{hint}"
        )
    return np.clip(joints, low, high)


# ---------------------------------------------------------------------------------------------- write


def atomic_write(path: Path, write) -> Path:
    """Call write(tmp_path) on a temporary file next to `path`, then move it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        write(Path(tmp))
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file ordinary permissions
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return path


def add_zip_member(archive: zipfile.ZipFile, name: str, data: bytes, compress: int) -> None:
    info = zipfile.ZipInfo(name, date_time=_FIXED_DATE)
    info.compress_type = compress
    info.external_attr = 0o644 << 16
    archive.writestr(info, data)


def joints_csv(rec: Recording) -> bytes:
    """joints.csv of a recording: header plus one row per step, t = step / fps."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_HEADER)
    for i, row in enumerate(rec.joints):
        writer.writerow([repr(i / rec.fps), *(repr(float(v)) for v in row)])
    return out.getvalue().encode("utf-8")


def write_zip(rec: Recording, path: Path, frames_as: Literal["png", "mp4"] = "png") -> Path:
    """Write `rec` as a format-v1 .zip (frames as PNG files or an mp4v video), atomically."""
    if frames_as not in ("png", "mp4"):
        raise ValueError(f"frames_as must be 'png' or 'mp4', got {frames_as!r}")
    meta = {"format": FORMAT_VERSION, "fps": rec.fps}
    if rec.utterance is not None:
        meta["utterance"] = rec.utterance

    def write(tmp: Path) -> None:
        with zipfile.ZipFile(tmp, "w") as archive:
            add_zip_member(archive, "joints.csv", joints_csv(rec), zipfile.ZIP_DEFLATED)
            add_zip_member(archive, "meta.json", json.dumps(meta, indent=1).encode(), zipfile.ZIP_DEFLATED)
            if frames_as == "png":
                width = max(5, len(str(rec.steps - 1)))
                for i, frame in enumerate(rec.frames):
                    ok, png = cv2.imencode(".png", cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
                    if not ok:
                        raise RecordingError(f"frame {i} could not be encoded as PNG")
                    add_zip_member(archive, f"frames/{i:0{width}d}.png", png.tobytes(), zipfile.ZIP_STORED)
            else:
                add_zip_member(archive, "video.mp4", _encode_mp4(rec), zipfile.ZIP_STORED)

    return atomic_write(path, write)


def _encode_mp4(rec: Recording) -> bytes:
    fd, tmp = tempfile.mkstemp(suffix=".mp4")
    os.close(fd)
    try:
        height, width = rec.frames.shape[1:3]
        writer = cv2.VideoWriter(tmp, cv2.VideoWriter_fourcc(*"mp4v"), rec.fps, (width, height))
        if not writer.isOpened():
            raise RecordingError("OpenCV cannot write mp4v video here; use frames_as='png'")
        for frame in rec.frames:
            writer.write(cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
        writer.release()
        return Path(tmp).read_bytes()
    finally:
        os.unlink(tmp)


def write_npz(rec: Recording, path: Path) -> Path:
    """Write `rec` as a format-v1 .npz (compressed, no pickles), atomically."""
    arrays: dict[str, np.ndarray] = {
        "joints": rec.joints.astype(np.float64),
        "frames": np.ascontiguousarray(rec.frames, dtype=np.uint8),
        "fps": np.array(rec.fps, dtype=np.float64),
    }
    if rec.utterance is not None:
        arrays["utterance"] = np.array(rec.utterance)

    def write(tmp: Path) -> None:
        with zipfile.ZipFile(tmp, "w") as archive:
            for key, array in arrays.items():
                buf = io.BytesIO()
                np.lib.format.write_array(buf, array, allow_pickle=False)
                add_zip_member(archive, f"{key}.npy", buf.getvalue(), zipfile.ZIP_DEFLATED)

    return atomic_write(path, write)
