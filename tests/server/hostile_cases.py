"""The crafted uploads of issue 14: each built here from bytes, for the tests and benchmarks/abuse.py.

`CASES` maps a name to a function returning a `Case` (where it is sent, the file name, the bytes).
Every case is small to send and cheap to build except `csv_3_5m_rows` (a 3.5-million-row
joints.csv, ~30 MB zipped) and `png_640x999999` (its header declares 640 x 999,999 pixels; the
pixel data is cut short, since an app that checks the header never reads it).
"""

from __future__ import annotations

import io
import json
import struct
import zipfile
import zlib
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
from PIL import Image

from data.nao import JOINT_LIMITS

HEADER = "t,RShoulderPitch,RShoulderRoll,RElbowYaw,RElbowRoll,RWristYaw"
DESCRIBE = "/api/describe"
SEEING = "/api/lessons/seeing"


@dataclass(frozen=True)
class Case:
    endpoint: str  # DESCRIBE (field "recording") or SEEING (field "image")
    filename: str
    data: bytes

    def files(self) -> dict[str, tuple[str, bytes]]:
        field = "recording" if self.endpoint == DESCRIBE else "image"
        return {field: (self.filename, self.data)}


def joints(steps: int = 30) -> np.ndarray:
    return np.repeat(JOINT_LIMITS.mean(axis=1)[None], steps, axis=0)


def csv_of(rows: np.ndarray, times: np.ndarray) -> bytes:
    lines = [HEADER] + [",".join(repr(float(v)) for v in (t, *q)) for t, q in zip(times, rows, strict=True)]
    return ("\n".join(lines) + "\n").encode()


def frame(width: int = 64, height: int = 48) -> np.ndarray:
    """An RGB frame: grey table, a red block."""
    image = np.full((height, width, 3), 120, np.uint8)
    image[height // 4 : height // 2, width // 4 : width // 2] = (220, 30, 30)
    return image


def png(rgb: np.ndarray) -> bytes:
    return cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))[1].tobytes()


def zip_of(members: dict[str, bytes], compress: int = zipfile.ZIP_DEFLATED) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compress, compresslevel=1) as z:
        for name, data in members.items():
            z.writestr(name, data)
    return buf.getvalue()


def recording_members(utterance: str | None = None, steps: int = 30) -> dict[str, bytes]:
    members = {"joints.csv": csv_of(joints(steps), np.arange(steps) / 20.0)}
    members |= {f"frames/{i:03d}.png": png(frame()) for i in range(3)}
    if utterance is not None:
        members["meta.json"] = json.dumps({"utterance": utterance}).encode()
    return members


def npz_of(**arrays: object) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


# ------------------------------------------------------------------------------------------ the cases


def unknown_word() -> Case:
    return Case(DESCRIBE, "word.zip", zip_of(recording_members("slide the red xylophonezz.")))


def digits_in_meta() -> Case:
    return Case(DESCRIBE, "digits.zip", zip_of(recording_members("push the 2 red apples.")))


def csv_cell_over_field_limit() -> Case:
    members = recording_members()
    members["joints.csv"] = members["joints.csv"].replace(b"\n0.05,", b"\n0.05" + b"0" * 200_000 + b",", 1)
    return Case(DESCRIBE, "cell.zip", zip_of(members))


def time_stamps_1_7e308() -> Case:
    members = recording_members()
    members["joints.csv"] = csv_of(joints(3), np.array([-1.7e308, 0.0, 1.7e308]))
    return Case(DESCRIBE, "times.zip", zip_of(members))


def npz_fps_5e_324() -> Case:
    return Case(DESCRIBE, "fps.npz", npz_of(joints=joints(), frames=np.stack([frame()] * 30), fps=5e-324))


def npz_fps_one_element_array() -> Case:
    data = npz_of(joints=joints(), frames=np.stack([frame()] * 30), fps=np.array([20.0]))
    return Case(DESCRIBE, "fps1.npz", data)


def npz_undecodable_utterance() -> Case:
    data = npz_of(joints=joints(), frames=np.stack([frame()] * 30), utterance=np.array(b"\xff\xfe push"))
    return Case(DESCRIBE, "utt.npz", data)


def deeply_nested_meta() -> Case:
    members = recording_members()
    members["meta.json"] = b"[" * 32_000 + b"]" * 32_000  # under the size limit of meta.json
    return Case(DESCRIBE, "nested.zip", zip_of(members))


def exif_rotated_jpeg() -> Case:
    """Two 64 x 48 JPEGs, the second tagged 'rotate 90' (EXIF orientation 6)."""
    members = recording_members()
    for name in [k for k in members if k.startswith("frames/")]:
        del members[name]
    plain, rotated = io.BytesIO(), io.BytesIO()
    Image.fromarray(frame()).save(plain, "JPEG")
    exif = Image.Exif()
    exif[0x0112] = 6
    Image.fromarray(frame()).save(rotated, "JPEG", exif=exif.tobytes())
    members |= {"frames/0.jpg": plain.getvalue(), "frames/1.jpg": rotated.getvalue()}
    return Case(DESCRIBE, "exif.zip", zip_of(members))


def encrypted_member() -> Case:
    """A zip whose joints.csv carries the 'encrypted' flag (bit 0) in both headers."""
    data = bytearray(zip_of(recording_members(), zipfile.ZIP_STORED))
    for signature, offset in ((b"PK\x03\x04", 6), (b"PK\x01\x02", 8)):
        at = data.find(signature)  # joints.csv is the first member
        flags = struct.unpack_from("<H", data, at + offset)[0]
        struct.pack_into("<H", data, at + offset, flags | 0x1)
    return Case(DESCRIBE, "encrypted.zip", bytes(data))


def npy_header_10e13_elements() -> Case:
    header = {"descr": "|u1", "fortran_order": False, "shape": (10**13 // 9216, 48, 64, 3)}
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    npy = buf.getvalue() + bytes(1024)
    good = io.BytesIO()
    np.lib.format.write_array(good, joints())
    return Case(DESCRIBE, "huge.npz", zip_of({"joints.npy": good.getvalue(), "frames.npy": npy}))


def frame_name_of_5000_digits() -> Case:
    members = recording_members()
    members["frames/" + "1" * 5000 + ".png"] = png(frame())
    return Case(DESCRIBE, "name.zip", zip_of(members))


def png_640x999999() -> Case:
    """A PNG whose header declares 640 x 999,999 RGB pixels (1.9 GB decoded), its data cut short."""

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    ihdr = struct.pack(">IIBBBBB", 640, 999_999, 8, 2, 0, 0, 0)
    idat = zlib.compress(bytes((640 * 3 + 1) * 2000))
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")
    return Case(SEEING, "tall.png", data)


def npz_1080p_fps_1_29() -> Case:
    """Two 1080p frames at fps 1/29: 29 s, ~580 steps of 1080p on the 20 Hz grid (3.5 GiB)."""
    frames = np.zeros((2, 1080, 1920, 3), np.uint8)
    data = npz_of(joints=joints(2), frames=frames, fps=1 / 29)
    return Case(DESCRIBE, "slow.npz", data)


def csv_3_5m_rows() -> Case:
    """A joints.csv of 3.5 million rows over 28 s (~150 MB), deflated well under the ratio limit."""
    mid = ",".join(repr(float(v)) for v in JOINT_LIMITS.mean(axis=1))
    text = "\n".join([HEADER, *(f"{i * 8e-6:.6f},{mid}" for i in range(3_500_000))]) + "\n"
    members = recording_members()
    members["joints.csv"] = text.encode()
    return Case(DESCRIBE, "rows.zip", zip_of(members))


CASES: dict[str, Callable[[], Case]] = {
    f.__name__: f
    for f in (
        unknown_word,
        digits_in_meta,
        csv_cell_over_field_limit,
        time_stamps_1_7e308,
        npz_fps_5e_324,
        npz_fps_one_element_array,
        npz_undecodable_utterance,
        deeply_nested_meta,
        exif_rotated_jpeg,
        encrypted_member,
        npy_header_10e13_elements,
        frame_name_of_5000_digits,
        png_640x999999,
        npz_1080p_fps_1_29,
        csv_3_5m_rows,
    )
}
