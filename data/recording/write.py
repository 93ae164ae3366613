"""Writing format v1: `write_zip` and `write_npz` (atomically, with fixed member timestamps so the
same recording gives the same bytes), and the two helpers the corpus writer shares."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Literal

import cv2
import numpy as np

from data.recording.format import CSV_HEADER, FORMAT_VERSION, Recording, RecordingError

_FIXED_DATE = (1980, 1, 1, 0, 0, 0)


def atomic_write(path: Path, write: Callable[[Path], None]) -> Path:
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
