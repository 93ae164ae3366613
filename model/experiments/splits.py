"""How the protocol divides recordings into training and test: the paper's split and harder ones.

Every split keeps the recordings of a scene on one side; they differ in which scenes are novel:

- ``scenes`` (the paper's 4.2, the default): a seeded 50:50 shuffle of the scenes.
- ``objects``: held-out colour x shape pairs. Fold k of 4 tests every action on the four objects
  (colour_i, shape_((i + k) mod 4)), a Latin square: each colour and each shape is held out once,
  so every word is still heard in training with three other partners; 4 folds cover all 16 objects.
- ``action-object``: held-out action x shape pairs, fold k tests (action_i, shape_((i + k) mod 4))
  in every colour, the same Latin square over actions and shapes.
- ``size``: the training-size curve. Per fold the seeded scene order's last quarter is the test
  set (16 of 64 scenes), and the first `train_scenes` of the other three quarters train (nested: a
  smaller size trains on a subset of a larger one, all against the same novel scenes).

Scenes are read from the teachers' utterances ("ACT the COL OBJ."), so a split needs no recording
ids of a particular format. Squares need a 4 x 4 grid of the two factors they pair.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from model.data import scene_key
from model.metrics import parse_slots

SPLITS = ("scenes", "objects", "action-object", "size")
SQUARE_FOLDS = 4  # folds of a Latin-square split (each covers one diagonal)
TRAINING_SIZES = (8, 16, 32, 48)  # scenes trained on for the training-size curve


def split_indices(
    ids: Sequence[str],
    utterances: Sequence[str],
    fold: int,
    split: str = "scenes",
    seed: int = 0,
    train_scenes: int | None = None,
) -> tuple[list[int], list[int]]:
    """(train, test) recording indices of one fold of `split`, each sorted."""
    if split == "scenes":
        return scene_split(ids, fold, seed)
    if split == "objects":
        return square_split(utterances, fold, ("colour", "object"))
    if split == "action-object":
        return square_split(utterances, fold, ("action", "object"))
    if split == "size":
        return size_split(ids, fold, train_scenes, seed)
    raise ValueError(f"unknown split {split!r}; expected one of {SPLITS}")


def scene_order(ids: Sequence[str], fold: int, seed: int = 0) -> tuple[list[str], list[str]]:
    """The scenes of `ids`, shuffled by a generator seeded with (seed, fold): the first half (rounded
    up) trains. Returns (scene key per recording, scenes in their shuffled order)."""
    keys = [scene_key(k) for k in ids]
    scenes = sorted(set(keys))
    if len(scenes) < 2:
        raise ValueError(f"a split by scene needs at least 2 scenes, got {len(scenes)}")
    order = np.random.default_rng([seed, fold]).permutation(len(scenes))
    return keys, [scenes[i] for i in order]


def scene_split(ids: Sequence[str], fold: int, seed: int = 0) -> tuple[list[int], list[int]]:
    """The paper's 50:50 split of recordings by scene (4.2)."""
    keys, ordered = scene_order(ids, fold, seed)
    train = set(ordered[: (len(ordered) + 1) // 2])
    return _sides(keys, train)


def size_split(
    ids: Sequence[str], fold: int, train_scenes: int | None, seed: int = 0
) -> tuple[list[int], list[int]]:
    """The training-size curve (module docstring): the last quarter of the seeded scene order is
    tested, the first `train_scenes` of the rest train."""
    keys, ordered = scene_order(ids, fold, seed)
    pool = len(ordered) - max(1, len(ordered) // 4)
    if train_scenes is None or not 1 <= train_scenes <= pool:
        raise ValueError(f"the size split needs train_scenes in 1..{pool}, got {train_scenes}")
    train_idx, _ = _sides(keys, set(ordered[:train_scenes]))
    _, test_idx = _sides(keys, set(ordered[:pool]))
    return train_idx, test_idx


def square_split(
    utterances: Sequence[str], fold: int, factors: tuple[str, str]
) -> tuple[list[int], list[int]]:
    """Hold out the Latin-square diagonal `fold` of the two `factors` (slot names of
    `model.metrics.parse_slots`): (first_i, second_((i + fold) mod 4)) for i = 0..3."""
    slots = [parse_slots(u) for u in utterances]
    first = sorted({s[factors[0]] for s in slots if s[factors[0]] is not None})
    second = sorted({s[factors[1]] for s in slots if s[factors[1]] is not None})
    if len(first) != SQUARE_FOLDS or len(second) != SQUARE_FOLDS:
        raise ValueError(
            f"a Latin square of {factors[0]} x {factors[1]} needs {SQUARE_FOLDS} of each, "
            f"got {len(first)} x {len(second)}"
        )
    if not 0 <= fold < SQUARE_FOLDS:
        raise ValueError(f"a Latin-square split has folds 0..{SQUARE_FOLDS - 1}, got {fold}")
    held = {(a, second[(i + fold) % SQUARE_FOLDS]) for i, a in enumerate(first)}
    pairs = [(s[factors[0]], s[factors[1]]) for s in slots]
    train = [i for i, p in enumerate(pairs) if p not in held]
    test = [i for i, p in enumerate(pairs) if p in held]
    return train, test


def held_out_pairs(utterances: Sequence[str], fold: int, factors: tuple[str, str]) -> list[tuple[str, str]]:
    """The pairs a square split's fold holds out, e.g. [("blue", "apple"), ...]."""
    _, test = square_split(utterances, fold, factors)
    slots = [parse_slots(utterances[i]) for i in test]
    return sorted({(s[factors[0]], s[factors[1]]) for s in slots})


def _sides(keys: Sequence[str], train: set[str]) -> tuple[list[int], list[int]]:
    return [i for i, k in enumerate(keys) if k in train], [i for i, k in enumerate(keys) if k not in train]
