"""Reading format v1: bytes or a file -> a `Recording` on the 20 Hz grid, or a `RecordingError`.

`read_recording` checks the file's size and the archive's members (unsafe paths, encryption,
decompression bombs) before anything is decompressed, then reads the zip
layout (joints.csv, meta.json and frames; `data.recording.joints` and `data.recording.frames`
parse those) or the npz layout (`data.recording.npz`).
"""

from __future__ import annotations

import json
import re
import zipfile
from pathlib import Path

from data.recording.archive import open_archive, open_member, read_member
from data.recording.format import (
    BOMB_MIN_MEMBER_BYTES,
    IMAGE_SUFFIXES,
    MAX_COMPRESSION_RATIO,
    MAX_MEMBERS,
    MAX_META_BYTES,
    MAX_UNCOMPRESSED_BYTES,
    MAX_UPLOAD_BYTES,
    VIDEO_NAMES,
    Recording,
    RecordingError,
    check_fps,
    check_utterance,
)
from data.recording.frames import read_images, read_video
from data.recording.joints import parse_joints_csv, resample_joints, time_grid
from data.recording.npz import is_npz, read_npz
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
    with open_archive(data, name) as archive:
        members = _check_members(archive, name)
        if is_npz(members):
            return read_npz(archive, members, name)
        return _read_zip(archive, members, name)


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
    """Reject unsafe member paths, encrypted members and decompression bombs before anything is
    decompressed; the members that matter (folders and OS clutter left out)."""
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
        if info.flag_bits & 0x1:
            raise RecordingError(
                f"{name}: member {info.filename!r} is encrypted (password-protected); "
                "save the recording as a plain zip without a password"
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


def _read_zip(archive: zipfile.ZipFile, infos: list[zipfile.ZipInfo], name: str) -> Recording:
    by_name = {i.filename.replace("\\", "/"): i for i in infos}
    prefix = _layout_prefix(by_name, name)
    files = {k[len(prefix) :]: v for k, v in by_name.items() if k.startswith(prefix)}

    with open_member(archive, files["joints.csv"], name) as stream:
        times, joints = parse_joints_csv(stream)
    meta = _parse_meta(archive, files["meta.json"], name) if "meta.json" in files else {}
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
        with open_member(archive, files[videos[0]], name) as stream:
            frames = read_video(stream, videos[0], grid, times, meta.get("fps"))
    elif images:
        frames = read_images(archive, [files[k] for k in images], name, grid, times, meta.get("fps"))
    else:
        raise RecordingError(
            f"{name} has no camera frames: add video.mp4 (or video.avi) or images frames/*.png|jpg"
        )
    return Recording(joints=joints, frames=frames, fps=FPS, utterance=meta.get("utterance"))


def _natural_key(name: str) -> list[tuple[int, int, str]]:
    """Name order with numbers compared as numbers: frame2.png before frame10.png (by length, then
    digits, leading zeros dropped, so that a number of any length compares without converting it)."""
    key = []
    for part in re.split(r"(\d+)", name):
        if part.isdigit():
            digits = part.lstrip("0")
            key.append((0, len(digits), digits))
        elif part:
            key.append((1, 0, part))
    return key


def _layout_prefix(by_name: dict[str, zipfile.ZipInfo], name: str) -> str:
    """'' when joints.csv is at the top, 'folder/' when the archive wraps one folder."""
    if "joints.csv" in by_name:
        return ""
    nested = [k for k in by_name if k.endswith("/joints.csv") and k.count("/") == 1]
    if len(nested) == 1:
        return nested[0][: -len("joints.csv")]
    listing = ", ".join(sorted(by_name)[:5]) + (" ..." if len(by_name) > 5 else "")
    raise RecordingError(f"{name} has no joints.csv at its top level (it holds: {listing})")


def _parse_meta(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str) -> dict:
    """The keys of meta.json this format uses (utterance, fps), checked; its size is bounded first."""
    if info.file_size > MAX_META_BYTES:
        raise RecordingError(
            f"meta.json is {info.file_size} bytes; at most {MAX_META_BYTES // 1024} KiB are accepted "
            '(it holds only {"utterance": ..., "fps": ...})'
        )
    try:
        meta = json.loads(read_member(archive, info, name).decode("utf-8-sig"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RecordingError(f"meta.json is not valid JSON ({exc})") from exc
    except RecursionError:
        raise RecordingError("meta.json is nested too deeply; it must be a flat JSON object") from None
    if not isinstance(meta, dict):
        raise RecordingError(
            f'meta.json must be a JSON object like {{"utterance": ...}}, got {type(meta).__name__}'
        )
    out: dict = {}
    if meta.get("utterance") is not None:
        out["utterance"] = check_utterance(meta["utterance"], "meta.json")
    if meta.get("fps") is not None:
        out["fps"] = check_fps(meta["fps"], "meta.json")
    return out
