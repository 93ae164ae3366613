"""Reading format v1: bytes or a file -> a `Recording` on the 20 Hz grid, or a `RecordingError`.

`read_recording` checks the file's size and the archive's members (unsafe paths, decompression
bombs) before anything is decompressed, then reads the zip layout (joints.csv, meta.json and
frames; `data.recording.joints` and `data.recording.frames` parse those) or the npz layout.
"""

from __future__ import annotations

import io
import json
import math
import re
import zipfile
import zlib
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

from data.nao import JOINT_NAMES
from data.recording.format import (
    BOMB_MIN_MEMBER_BYTES,
    IMAGE_SUFFIXES,
    MAX_COMPRESSION_RATIO,
    MAX_MEMBERS,
    MAX_UNCOMPRESSED_BYTES,
    MAX_UPLOAD_BYTES,
    MAX_UTTERANCE_CHARS,
    VIDEO_NAMES,
    Recording,
    RecordingError,
    check_frame_array,
    check_size,
)
from data.recording.frames import check_memory, frame_times, nearest_frames, read_video
from data.recording.joints import check_limits, parse_joints_csv, resample_joints, time_grid
from data.world import FPS

_IGNORED = re.compile(r"(^|/)(__MACOSX/|\.DS_Store$|Thumbs\.db$)")


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

    times, joints = parse_joints_csv(_read_member(archive, files["joints.csv"], name))
    meta = _parse_meta(_read_member(archive, files["meta.json"], name)) if "meta.json" in files else {}
    grid = time_grid(times[0], times[-1])
    joints = resample_joints(times, joints, grid)

    videos = [v for v in VIDEO_NAMES if v in files]
    images = sorted(
        (k for k in files if k.startswith("frames/") and k.lower().endswith(IMAGE_SUFFIXES)), key=_natural_key
    )
    if len(videos) > 1 or (videos and images):
        found = ", ".join(videos + (["frames/"] if images else []))
        raise RecordingError(f"{name} holds more than one set of frames ({found}); keep exactly one")
    if videos:
        data = _read_member(archive, files[videos[0]], name)
        frames = read_video(data, videos[0], grid, times, meta.get("fps"))
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
            check_size(*this, info.filename)
            check_memory(len(grid), *this)
            size = this
        elif this != size:
            raise RecordingError(
                f"{info.filename} is {this[0]}x{this[1]} but the first frame is {size[0]}x{size[1]}; "
                "all frames must have the same size"
            )
        blobs.append(blob)
    picks = nearest_frames(
        grid, frame_times(len(blobs), times[0], times[-1], fps), "frames/", times[-1] - times[0]
    )
    decoded: dict[int, np.ndarray] = {}
    for i in np.unique(picks):
        bgr = cv2.imdecode(np.frombuffer(blobs[i], np.uint8), cv2.IMREAD_COLOR)
        if bgr is None:
            raise RecordingError(f"{infos[i].filename} cannot be decoded as an image")
        decoded[int(i)] = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    return np.stack([decoded[int(i)] for i in picks])


# ---------------------------------------------------------------------------------------- npz layout


def _read_npz(data: bytes, name: str) -> Recording:
    arrays = _npz_arrays(data, name)
    joints = _npz_joints(arrays["joints"], name)
    frames = arrays["frames"]
    check_frame_array(frames, f"{name}: frames")
    if len(frames) != len(joints):
        raise RecordingError(
            f"{name}: joints have {len(joints)} steps but frames have {len(frames)}; "
            "there must be one frame per joint sample"
        )
    fps = _npz_fps(arrays["fps"], name) if "fps" in arrays else FPS
    utterance = _npz_utterance(arrays["utterance"], name) if "utterance" in arrays else None
    times = np.arange(len(joints)) / fps
    joints = check_limits(joints, lambda i: f"step {i} (t = {times[i]:g} s)")
    grid = time_grid(0.0, times[-1])
    if fps != FPS:
        joints = resample_joints(times, joints, grid)
        frames = frames[nearest_frames(grid, times, name, times[-1])]
    return Recording(joints=joints, frames=np.ascontiguousarray(frames), fps=FPS, utterance=utterance)


def _npz_arrays(data: bytes, name: str) -> dict[str, np.ndarray]:
    """The arrays a .npz recording may hold (joints and frames required), never unpickling."""
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
        return {k: _npz_array(npz, k, name) for k in ("joints", "frames", "fps", "utterance") if k in keys}


def _npz_joints(joints: np.ndarray, name: str) -> np.ndarray:
    """The joints array as T x 5 finite float64 radians."""
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
    return joints


def _npz_fps(value: np.ndarray, name: str) -> float:
    if value.size != 1 or value.dtype.kind not in "fiu" or not np.isfinite(value).all() or float(value) <= 0:
        raise RecordingError(f"{name}: fps must be one positive number, got {value!r}")
    return float(value.reshape(()))


def _npz_utterance(value: np.ndarray, name: str) -> str:
    if value.dtype.kind not in "US" or value.size != 1:
        raise RecordingError(
            f"{name}: utterance must be a single string, got an array of dtype {value.dtype}"
        )
    text = value.reshape(()).item()
    return _check_utterance(text.decode("utf-8") if isinstance(text, bytes) else text, name)


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
