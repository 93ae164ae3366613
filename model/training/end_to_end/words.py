"""The words the learner heard: `WordSlots` reads slots of phrases off the heard utterances.

A word said in every utterance carries nothing; words that always occur together form one phrase
(e.g. "show me"); the k-th remaining phrase of a sentence is slot k.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from model.encoding.words import words_of


@dataclass(frozen=True)
class WordSlots:
    """Slots of phrases read off heard utterances: slot k holds every phrase heard k-th."""

    slots: tuple[tuple[str, ...], ...]

    @classmethod
    def from_utterances(cls, utterances: Sequence[str]) -> WordSlots:
        sentences = [words_of(u) for u in utterances]
        heard_in: dict[str, frozenset[int]] = {}
        for i, words in enumerate(sentences):
            for w in words:
                heard_in[w] = heard_in.get(w, frozenset()) | {i}
        phrased = [cls._phrases(words, heard_in, len(sentences)) for words in sentences]
        counts = {len(p) for p in phrased}
        if len(counts) != 1:
            raise ValueError(f"utterances have different numbers of informative phrases: {sorted(counts)}")
        slots = tuple(tuple(sorted({p[k] for p in phrased})) for k in range(counts.pop()))
        return cls(slots)

    @staticmethod
    def _phrases(words: list[str], heard_in: dict[str, frozenset[int]], n: int) -> list[str]:
        """Drop words said in every utterance; join neighbours always heard together."""
        phrases: list[list[str]] = []
        previous = None
        for w in words:
            if len(heard_in.get(w, ())) == n:
                previous = None
                continue
            if previous is not None and heard_in.get(previous) == heard_in.get(w):
                phrases[-1].append(w)
            else:
                phrases.append([w])
            previous = w
        return [" ".join(p) for p in phrases]

    @property
    def sizes(self) -> list[int]:
        return [len(s) for s in self.slots]

    def indices(self, utterance: str) -> list[int]:
        """Index of the heard phrase within each slot (ValueError if one is unknown)."""
        text = " ".join(words_of(utterance))
        out = []
        for slot in self.slots:
            found = [k for k, phrase in enumerate(slot) if re.search(rf"\b{re.escape(phrase)}\b", text)]
            if len(found) != 1:
                raise ValueError(f"{utterance!r} has no single phrase of slot {slot}")
            out.append(found[0])
        return out

    def one_hot(self, utterances: Sequence[str]) -> Tensor:
        """p*: the heard words as word-unit activity [B, sum(sizes)], one 1 per slot."""
        return self.activity([self.indices(u) for u in utterances])

    def activity(self, phrases: Sequence[Sequence[int]]) -> Tensor:
        """Word-unit activity [B, sum(sizes)] of phrase indices per slot [B][slots], one 1 per slot."""
        out = torch.zeros(len(phrases), sum(self.sizes))
        offsets = np.cumsum([0, *self.sizes[:-1]])
        for i, indices in enumerate(phrases):
            for offset, k in zip(offsets, indices, strict=True):
                out[i, offset + k] = 1.0
        return out
