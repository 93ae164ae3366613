"""Proprioception encoding (paper 4.1.1): joint angles scaled to [0, 1] by the joint limits.

"The resulting values are scaled to [0, 1], based on the minimal and maximal joint positions."
The limits are an argument (for the NAO: ``data.nao.JOINT_LIMITS``) so that ``model/`` does not
depend on ``data/``. Angles outside the limits are clipped to the nearest limit.

    >>> import numpy as np
    >>> limits = np.array([[-1.0, 1.0]] * 5)
    >>> encode_joints(np.zeros((2, 5)), limits)[0]
    array([0.5, 0.5, 0.5, 0.5, 0.5], dtype=float32)
"""

from __future__ import annotations

import numpy as np

JOINTS = 5


def _check_limits(limits: np.ndarray) -> np.ndarray:
    lim = np.asarray(limits, dtype=np.float64)
    if lim.shape != (JOINTS, 2):
        raise ValueError(
            f"joint limits must have shape ({JOINTS}, 2) as [min, max] per joint, got {lim.shape}"
        )
    if not np.all(np.isfinite(lim)):
        raise ValueError("joint limits contain NaN or infinite values")
    if np.any(lim[:, 1] <= lim[:, 0]):
        bad = np.flatnonzero(lim[:, 1] <= lim[:, 0]).tolist()
        raise ValueError(f"joint limits must satisfy min < max; joints {bad} do not")
    return lim


def _check_sequence(values: np.ndarray, what: str) -> np.ndarray:
    arr = np.asarray(values)
    if not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise ValueError(f"{what} must be numeric, got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != JOINTS:
        raise ValueError(f"{what} must have shape (T, {JOINTS}) (time steps x joints), got {arr.shape}")
    if arr.shape[0] == 0:
        raise ValueError(f"{what} is empty (0 time steps)")
    arr = arr.astype(np.float64)
    if not np.all(np.isfinite(arr)):
        rows = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        raise ValueError(
            f"{what} contain NaN or infinite values at {rows.size} time step(s), first at t={rows[0]}"
        )
    return arr


def encode_joints(joints: np.ndarray, limits: np.ndarray) -> np.ndarray:
    """Scale joint angles ``[T, 5]`` (radians) to ``[T, 5]`` float32 in [0, 1] by ``limits [5, 2]``."""
    lim = _check_limits(limits)
    q = _check_sequence(joints, "joint angles")
    scaled = (q - lim[:, 0]) / (lim[:, 1] - lim[:, 0])
    return np.clip(scaled, 0.0, 1.0).astype(np.float32)


def decode_joints(encoded: np.ndarray, limits: np.ndarray) -> np.ndarray:
    """Inverse of :func:`encode_joints`: values in [0, 1] (clipped) back to radians, float64."""
    lim = _check_limits(limits)
    y = np.clip(_check_sequence(encoded, "encoded joint values"), 0.0, 1.0)
    return lim[:, 0] + y * (lim[:, 1] - lim[:, 0])
