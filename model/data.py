"""What training needs to know about a set of recordings, and nothing about where they came from:
the encoded sequences (`SequenceSet`) and the scene a recording id belongs to (`scene_key`)."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np


def scene_key(recording_id: str) -> str:
    """ "slide-red-apple-2" -> "slide-red-apple" (the variant suffix "-N" removed, if any)."""
    return re.sub(r"-\d+$", "", recording_id)


@dataclass
class SequenceSet:
    """Encoded recordings: one entry per recording, sequences of varying length."""

    proprioception: list[np.ndarray]  # each [T_i, 5] in [0, 1]
    vision: list[np.ndarray]  # each [T_i, F] visual features (19 paper features, +2 centroid optional)
    utterances: list[str]  # what the teacher said, e.g. "slide the red apple."
    ids: list[str]  # recording ids, for reports and plots
    # The arm the joint codes belong to (`model.encoding.kinematics.ArmChain.to_dict()`), for
    # readings that need its kinematics (end_to_end's `hand_path`); None if not known.
    arm: dict | None = None

    def __post_init__(self) -> None:
        n = len(self.ids)
        if not (len(self.proprioception) == len(self.vision) == len(self.utterances) == n):
            raise ValueError("proprioception, vision, utterances and ids must have one entry per recording")

    def __len__(self) -> int:
        return len(self.ids)

    def subset(self, indices: list[int] | np.ndarray) -> SequenceSet:
        idx = [int(i) for i in indices]
        return SequenceSet(
            [self.proprioception[i] for i in idx],
            [self.vision[i] for i in idx],
            [self.utterances[i] for i in idx],
            [self.ids[i] for i in idx],
            self.arm,
        )
