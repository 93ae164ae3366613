"""joints.csv and the time grid: parsing (streamed, rows counted while reading) and validating the
joint table, the 20 Hz grid with its length limits, resampling onto it, and the NAO joint limits
every recording must keep."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Iterator
from typing import IO

import numpy as np

from data.nao import JOINT_LIMITS, JOINT_NAMES
from data.recording.format import (
    CSV_HEADER,
    LIMIT_TOLERANCE,
    MAX_CSV_LINE_BYTES,
    MAX_JOINT_ROWS,
    MAX_STEPS,
    MIN_STEPS,
    RecordingError,
)
from data.world import FPS


def parse_joints_csv(source: bytes | IO[bytes]) -> tuple[np.ndarray, np.ndarray]:
    """Times [N] in seconds and angles [N, 5] in radians (JOINT_NAMES order), validated.

    `source` is read line by line: the rows are counted (at most MAX_JOINT_ROWS) and each line's
    length is bounded (MAX_CSV_LINE_BYTES) while reading, so a huge table is refused early."""
    stream = io.BytesIO(source) if isinstance(source, bytes | bytearray) else source
    rows = _csv_rows(stream)
    first = next(rows, None)
    if first is None:
        raise RecordingError("joints.csv is empty; its first line must be the header " + ",".join(CSV_HEADER))
    header = _check_header(first)
    order = [header.index(c) for c in CSV_HEADER]
    body: list[list[float]] = []
    for r, row in enumerate(rows):
        line = r + 2
        if r == MAX_JOINT_ROWS:
            raise RecordingError(
                f"joints.csv has more than {MAX_JOINT_ROWS} rows; resample it to at most "
                f"{MAX_JOINT_ROWS // 30} Hz (the model reads 20 Hz)"
            )
        if len(row) != len(header):
            raise RecordingError(f"joints.csv line {line} has {len(row)} values; expected {len(header)}")
        body.append([_cell_value(row[col].strip(), line, CSV_HEADER[j]) for j, col in enumerate(order)])
    if not body:
        raise RecordingError("joints.csv has a header but no data rows")
    values = np.array(body, dtype=np.float64)
    times = values[:, 0]
    steps = np.diff(times)
    if np.any(steps <= 0):
        k = int(np.argmax(steps <= 0))
        raise RecordingError(
            f"joints.csv: time goes from {times[k]:g} s (line {k + 2}) to {times[k + 1]:g} s "
            f"(line {k + 3}); t must be strictly increasing"
        )
    joints = check_limits(values[:, 1:], lambda i: f"t = {times[i]:g} s (joints.csv line {i + 2})")
    return times, joints


def _csv_rows(stream: IO[bytes]) -> Iterator[list[str]]:
    """The non-blank rows of joints.csv (UTF-8, with or without a byte-order mark), read lazily."""
    reader = csv.reader(_lines(stream))
    try:
        for row in reader:
            if any(cell.strip() for cell in row):
                yield row
    except csv.Error as exc:
        raise RecordingError(f"joints.csv line {reader.line_num} cannot be read as CSV ({exc})") from None


def _lines(stream: IO[bytes]) -> Iterator[str]:
    """The lines of `stream` as text, none longer than MAX_CSV_LINE_BYTES."""
    number = 0
    while line := stream.readline(MAX_CSV_LINE_BYTES + 1):
        number += 1
        if len(line) > MAX_CSV_LINE_BYTES:
            raise RecordingError(
                f"joints.csv line {number} is longer than {MAX_CSV_LINE_BYTES} bytes; "
                "a row holds six numbers: t and the five joint angles"
            )
        try:
            yield line.decode("utf-8-sig" if number == 1 else "utf-8")
        except UnicodeDecodeError:
            raise RecordingError("joints.csv is not UTF-8 text") from None


def _check_header(first: list[str]) -> list[str]:
    """The header's column names: exactly those of `CSV_HEADER`, each once, in any order."""
    header = [c.strip() for c in first]
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
    return header


def _cell_value(cell: str, line: int, column: str) -> float:
    """One cell of joints.csv as a finite number."""
    try:
        value = float(cell)
    except ValueError:
        raise RecordingError(f"joints.csv line {line}, column {column}: {cell!r} is not a number") from None
    if not math.isfinite(value):
        raise RecordingError(f"joints.csv line {line}, column {column}: {cell!r} is not a finite number")
    return value


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def time_grid(t0: float, t1: float) -> np.ndarray:
    """The 20 Hz grid over [t0, t1], with the length checks (made before the grid is built)."""
    span = float(t1) - float(t0)  # Python floats: inf on overflow, without a warning
    if not math.isfinite(span) or span * FPS > 2 * MAX_STEPS:
        raise RecordingError(
            f"the recording is too long: its time stamps run from {t0:g} s to {t1:g} s; "
            f"at most {MAX_STEPS / FPS:g} s ({MAX_STEPS} steps) is accepted"
        )
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


def resample_joints(times: np.ndarray, joints: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Linear interpolation of each joint onto the 20 Hz grid."""
    return np.stack([np.interp(grid, times, joints[:, j]) for j in range(joints.shape[1])], axis=1)


def check_limits(joints: np.ndarray, where: Callable[[int], str]) -> np.ndarray:
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
