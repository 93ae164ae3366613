"""joints.csv and the time grid: parsing and validating the joint table, the 20 Hz grid with its
length limits, resampling onto it, and the NAO joint limits every recording must keep."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable

import numpy as np

from data.nao import JOINT_LIMITS, JOINT_NAMES
from data.recording.format import CSV_HEADER, LIMIT_TOLERANCE, MAX_STEPS, MIN_STEPS, RecordingError
from data.world import FPS


def parse_joints_csv(raw: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Times [N] in seconds and angles [N, 5] in radians (JOINT_NAMES order), validated."""
    rows = _csv_rows(raw)
    header = _check_header(rows[0])
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
            values[r, j] = _cell_value(row[col].strip(), line, CSV_HEADER[j])
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


def _csv_rows(raw: bytes) -> list[list[str]]:
    """The non-blank rows of joints.csv (UTF-8, with or without a byte-order mark); at least one."""
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RecordingError("joints.csv is not UTF-8 text") from exc
    rows = [r for r in csv.reader(io.StringIO(text)) if any(cell.strip() for cell in r)]
    if not rows:
        raise RecordingError("joints.csv is empty; its first line must be the header " + ",".join(CSV_HEADER))
    return rows


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
