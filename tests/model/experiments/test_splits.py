"""The protocol's splits: the paper's 50:50 by scene (unchanged), held-out objects and action x
shape pairs in Latin squares, and the nested training-size curve, on the shipped corpus's ids."""

from __future__ import annotations

import hashlib
import json

import pytest

from model.data import scene_key
from model.experiments.splits import (
    SPLITS,
    SQUARE_FOLDS,
    TRAINING_SIZES,
    held_out_pairs,
    scene_split,
    split_indices,
)
from model.metrics import parse_slots

ACTIONS = ("pull", "push", "show me", "slide")
COLOURS = ("blue", "green", "red", "yellow")
SHAPES = ("apple", "banana", "dice", "phone")
# the corpus's recordings in its order (data.scenario.all_scenes x 4 variants)
IDS = [
    f"{a.replace(' ', '-')}-{c}-{s}-{k}" for a in ACTIONS for c in COLOURS for s in SHAPES for k in range(4)
]
TEXTS = [f"{a} the {c} {s}." for a in ACTIONS for c in COLOURS for s in SHAPES for _ in range(4)]
# stored when the split moved here from evaluation.fold_split: the paper's folds must not move
FOLD0_FIRST_TEST = [
    "pull-blue-apple-0",
    "pull-blue-apple-1",
    "pull-blue-apple-2",
    "pull-blue-apple-3",
    "pull-green-banana-0",
    "pull-green-banana-1",
    "pull-green-banana-2",
    "pull-green-banana-3",
]
FOLDS_0_TO_9_TEST_SHA256 = "0db2c991f70ccf1a5bc6d07726af8abdc9b3f51fd120eafe30849d05616e8ae3"


def test_the_corpus_ids_are_the_shipped_corpus_order() -> None:
    from data.scenario import all_scenes, recording_id

    assert [recording_id(s, k) for s in all_scenes() for k in range(4)] == IDS


def test_the_scenes_split_gives_the_folds_it_always_gave() -> None:
    tests = [scene_split(IDS, k)[1] for k in range(10)]
    assert [IDS[i] for i in tests[0][:8]] == FOLD0_FIRST_TEST
    assert hashlib.sha256(json.dumps(tests).encode()).hexdigest() == FOLDS_0_TO_9_TEST_SHA256
    assert all(split_indices(IDS, TEXTS, k) == scene_split(IDS, k) for k in range(10))


@pytest.mark.parametrize("fold", [0, 1, 7])
def test_the_scenes_split_keeps_scenes_whole_and_halves_them(fold: int) -> None:
    train_idx, test_idx = scene_split(IDS, fold)
    assert sorted(train_idx + test_idx) == list(range(len(IDS)))
    train_scenes = {scene_key(IDS[i]) for i in train_idx}
    test_scenes = {scene_key(IDS[i]) for i in test_idx}
    assert not train_scenes & test_scenes and len(train_scenes) == len(test_scenes) == 32
    assert train_idx == sorted(train_idx) and test_idx == sorted(test_idx)


def test_the_scenes_split_is_seeded_per_fold() -> None:
    assert scene_split(IDS, 3, seed=1) == scene_split(IDS, 3, seed=1)
    assert len({tuple(scene_split(IDS, k)[0]) for k in range(10)}) == 10
    assert scene_split(IDS, 0, seed=0) != scene_split(IDS, 0, seed=1)


@pytest.mark.parametrize(
    ("split", "factors"), [("objects", ("colour", "object")), ("action-object", ("action", "object"))]
)
def test_a_square_split_holds_out_a_latin_square_and_its_folds_cover_every_pair(split, factors) -> None:
    covered: set[tuple[str, str]] = set()
    for fold in range(SQUARE_FOLDS):
        train_idx, test_idx = split_indices(IDS, TEXTS, fold, split)
        held = held_out_pairs(TEXTS, fold, factors)
        assert len(held) == 4 and len(test_idx) == 64 and len(train_idx) == 192
        assert len({a for a, _ in held}) == len({b for _, b in held}) == 4  # each word held out once
        slots = [parse_slots(TEXTS[i]) for i in train_idx]
        assert not {(s[factors[0]], s[factors[1]]) for s in slots} & set(held)
        for k in (0, 1):  # every word is still heard in training, with three other partners
            assert len({s[factors[k]] for s in slots}) == 4
        covered |= set(held)
    assert len(covered) == 16


def test_a_square_split_refuses_a_fifth_fold_and_a_grid_that_is_not_four_by_four() -> None:
    with pytest.raises(ValueError, match="folds 0..3"):
        split_indices(IDS, TEXTS, 4, "objects")
    with pytest.raises(ValueError, match="needs 4 of each"):
        split_indices(IDS[:32], TEXTS[:32], 0, "objects")  # pull only, blue and green


def test_the_size_split_trains_on_nested_scenes_against_the_same_novel_ones() -> None:
    sides = {n: split_indices(IDS, TEXTS, 2, "size", train_scenes=n) for n in TRAINING_SIZES}
    tests = {tuple(test) for _, test in sides.values()}
    assert len(tests) == 1 and len(next(iter(tests))) == 16 * 4
    for small, large in zip(TRAINING_SIZES, TRAINING_SIZES[1:], strict=False):
        assert set(sides[small][0]) < set(sides[large][0])
    for n, (train, test) in sides.items():
        assert len({scene_key(IDS[i]) for i in train}) == n and not set(train) & set(test)


def test_the_size_split_needs_a_size_and_an_unknown_split_is_named() -> None:
    with pytest.raises(ValueError, match="train_scenes in 1..48"):
        split_indices(IDS, TEXTS, 0, "size")
    with pytest.raises(ValueError, match="train_scenes in 1..48"):
        split_indices(IDS, TEXTS, 0, "size", train_scenes=49)
    with pytest.raises(ValueError, match="unknown split 'colours'"):
        split_indices(IDS, TEXTS, 0, "colours")
    assert SPLITS == ("scenes", "objects", "action-object", "size")
