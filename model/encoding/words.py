"""Words of a sentence and the weighted edit distance between symbol sequences.

The lexicon's nearest word (`model.encoding.utterance.Lexicon.nearest`) and the paper's utterance
measures (`model.metrics`, 4.3) both rest on these: `words_of` reads a sentence's words, `align`
is the weighted Levenshtein alignment with insertion 1, deletion 1, substitution 2. A substitution
costs exactly a deletion plus an insertion, so the minimum distance is
``|produced| + |target| - 2 * LCS`` and the matched pairs of the alignment are a longest common
subsequence.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

INSERTION_COST = 1.0
DELETION_COST = 1.0
SUBSTITUTION_COST = 2.0

EditOp = Literal["match", "sub", "ins", "del"]

_WORD = re.compile(r"[a-z']+")


def words_of(text: str) -> list[str]:
    """Lower-case words of a sentence, punctuation dropped."""
    return _WORD.findall(text.lower())


@dataclass(frozen=True)
class Alignment:
    """A minimum-edit alignment of `produced` against `target`.

    `pairs` lists ``(op, produced_index, target_index)`` in order; an index is None where the op
    has no symbol on that side ("ins": an extra produced symbol, "del": a missing target symbol).
    """

    distance: float
    pairs: tuple[tuple[EditOp, int | None, int | None], ...]

    @property
    def matches(self) -> int:
        return sum(1 for op, _, _ in self.pairs if op == "match")


def align(
    produced: Sequence[str],
    target: Sequence[str],
    ins: float = INSERTION_COST,
    dele: float = DELETION_COST,
    sub: float = SUBSTITUTION_COST,
) -> Alignment:
    """Weighted Levenshtein alignment (dynamic programming, deterministic tie-breaking).

    Costs: `ins` for a produced symbol absent from the target, `dele` for a target symbol the
    production missed, `sub` for a wrong symbol in place of a target one. On ties the backtrace
    prefers match/substitution, then deletion, then insertion.
    """
    n, m = len(produced), len(target)
    cost = np.zeros((n + 1, m + 1))
    cost[:, 0] = np.arange(n + 1) * ins
    cost[0, :] = np.arange(m + 1) * dele
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            diag = cost[i - 1, j - 1] + (0.0 if produced[i - 1] == target[j - 1] else sub)
            cost[i, j] = min(diag, cost[i, j - 1] + dele, cost[i - 1, j] + ins)
    pairs: list[tuple[EditOp, int | None, int | None]] = []
    i, j = n, m
    while i > 0 or j > 0:
        if i > 0 and j > 0:
            same = produced[i - 1] == target[j - 1]
            if math.isclose(cost[i, j], cost[i - 1, j - 1] + (0.0 if same else sub)):
                pairs.append(("match" if same else "sub", i - 1, j - 1))
                i, j = i - 1, j - 1
                continue
        if j > 0 and math.isclose(cost[i, j], cost[i, j - 1] + dele):
            pairs.append(("del", None, j - 1))
            j -= 1
        else:
            pairs.append(("ins", i - 1, None))
            i -= 1
    return Alignment(distance=float(cost[n, m]), pairs=tuple(reversed(pairs)))


def raw_edit_distance(produced: Sequence[str], target: Sequence[str], **costs: float) -> float:
    """The unnormalised weighted edit distance (`costs`: `align`'s ins, dele, sub)."""
    return align(produced, target, **costs).distance
