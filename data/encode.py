"""Recording -> encoded features: the one function the corpus, the server and the benchmarks call.

A `Recording` (joint angles and camera frames at `data.world.FPS`) becomes what the model reads
(paper 4.1.1): proprioception, the joint angles scaled by the NAO's joint limits into [0, 1], and
vision, the OpenCV pipeline's 16 salient distances, mean RGB and centroid per frame. Nothing here
knows whether the recording was simulated or uploaded.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from data.nao import JOINT_LIMITS
from data.recording import Recording
from model.encoding.proprioception import encode_joints
from model.encoding.vision import encode_frames_found


@dataclass(frozen=True)
class Features:
    """What the MultiMTRNN reads of one recording."""

    proprioception: np.ndarray  # [T, 5] in [0, 1]
    vision: np.ndarray  # [T, 21] float32: 16 distances, mean R, G, B, centroid x, y
    object_found: np.ndarray  # [T] bool: frames in which the vision pipeline found the object


def encode_recording(recording: Recording, workers: int = 2) -> Features:
    """Encode `recording` as the model reads it; `workers` threads share the frames."""
    vision, found = encode_frames_found(recording.frames, workers=workers)
    return Features(encode_joints(recording.joints, JOINT_LIMITS), vision, found)
