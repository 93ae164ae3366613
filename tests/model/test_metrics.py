"""Evaluation measures (paper 3.2.2 and 4.3) on hand-computed examples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from model.metrics import (
    CscPCA,
    Transcript,
    align,
    d_avg,
    d_inter,
    d_intra,
    d_rel,
    edit_distance,
    mixed,
    pairwise_distances,
    parse_slots,
    phoneme_f1,
    raw_edit_distance,
    sentence_exact,
    slot_accuracy,
    summarise,
    word_accuracy,
)

ACTIONS = ("pull", "push", "show me", "slide")
COLOURS = ("blue", "green", "red", "yellow")
OBJECTS = ("apple", "banana", "dice", "phone")


def test_edit_weights_insertion_1_deletion_1_substitution_2() -> None:
    assert raw_edit_distance(["P", "AH"], ["P"]) == 1.0  # one extra produced phoneme
    assert raw_edit_distance(["P"], ["P", "AH"]) == 1.0  # one missing target phoneme
    assert raw_edit_distance(["B"], ["P"]) == 2.0  # substitution = deletion + insertion
    assert raw_edit_distance(["B"], ["P"], sub=1.0) == 1.0
    assert raw_edit_distance(["P", "UH", "L"], ["P", "UH", "L"]) == 0.0


def test_edit_distance_is_normalised_by_target_length() -> None:
    assert edit_distance(["P", "IY", "L"], ["P", "UH", "L", "Z"]) == pytest.approx(3.0 / 4.0)
    assert edit_distance([], ["A", "B"]) == 1.0
    assert edit_distance(["A"], []) == 1.0


def test_alignment_lists_operations_in_order() -> None:
    alignment = align(["P", "IY", "L"], ["P", "L", "Z"])
    assert alignment.distance == 2.0
    assert [op for op, _, _ in alignment.pairs] == ["match", "ins", "match", "del"]
    assert alignment.pairs[1] == ("ins", 1, None)
    assert alignment.pairs[3] == ("del", None, 2)


def test_f1_on_a_worked_alignment() -> None:
    # produced P UH L L AH vs target P UH SH AH: matched P, UH, AH (3)
    produced = ["P", "UH", "L", "L", "AH"]
    target = ["P", "UH", "SH", "AH"]
    precision, recall, f1 = phoneme_f1(produced, target)
    assert precision == pytest.approx(3 / 5)
    assert recall == pytest.approx(3 / 4)
    assert f1 == pytest.approx(2 * 0.6 * 0.75 / 1.35)
    assert raw_edit_distance(produced, target) == 5 + 4 - 2 * 3


def test_f1_edge_cases() -> None:
    assert phoneme_f1([], []) == (1.0, 1.0, 1.0)
    assert phoneme_f1([], ["A"]) == (0.0, 0.0, 0.0)
    assert phoneme_f1(["A"], ["B"]) == (0.0, 0.0, 0.0)


def test_sentence_exact_ignores_case_and_spacing_only() -> None:
    assert sentence_exact("Pull  the blue apple.", "pull the blue apple.")
    assert not sentence_exact("pull the blue apple", "pull the blue apple.")
    assert not sentence_exact("push the blue apple.", "pull the blue apple.")


def test_word_accuracy() -> None:
    assert word_accuracy("pull the red apple.", "pull the blue apple.") == 0.75
    assert word_accuracy("show me the red apple.", "pull the red apple.") == 3 / 5
    assert word_accuracy("pull the blue apple.", "pull the blue apple.") == 1.0


def test_slots_of_grammar_sentences() -> None:
    assert parse_slots("show me the green dice.") == {
        "action": "show me",
        "colour": "green",
        "object": "dice",
    }
    assert slot_accuracy("push the red apple.", "pull the red apple.") == {
        "action": 0.0, "colour": 1.0, "object": 1.0,
    }  # fmt: skip


def test_garbled_sentence_scores_zero_on_unreadable_slots() -> None:
    # positional reading: only one word after "the", so colour and object are unreadable
    assert slot_accuracy("pull the blue.", "pull the blue apple.") == {
        "action": 1.0, "colour": 0.0, "object": 0.0,
    }  # fmt: skip
    assert slot_accuracy("", "pull the blue apple.") == {"action": 0.0, "colour": 0.0, "object": 0.0}
    # with vocabularies each slot is read on its own
    assert slot_accuracy("pull blue blue apple.", "pull the blue apple.", ACTIONS, COLOURS, OBJECTS) == {
        "action": 1.0, "colour": 1.0, "object": 1.0,
    }  # fmt: skip
    assert (
        slot_accuracy("show the blue apple.", "show me the blue apple.", ACTIONS, COLOURS, OBJECTS)["action"]
        == 0.0
    )
    assert (
        slot_accuracy("pull the blue red apple.", "pull the blue apple.", ACTIONS, COLOURS, OBJECTS)["colour"]
        == 0.0
    )
    with pytest.raises(ValueError, match="target"):
        slot_accuracy("pull the blue apple.", "hello")


def test_mixed_is_the_mean_of_train_and_test() -> None:
    assert mixed(0.952, 0.281) == pytest.approx(0.6165)


def test_summarise_means_over_a_split() -> None:
    target = Transcript(("SIL", "P", "UH", "L", "PER"), "pull the blue apple.")
    wrong = Transcript(("SIL", "P", "UH", "SH", "PER"), "push the blue apple.")
    summary = summarise([(target, target), (wrong, target)])
    assert summary["n"] == 2
    assert summary["sentence_exact"] == 0.5
    assert summary["edit_distance"] == pytest.approx((0 + 2 / 5) / 2)
    assert summary["f1"] == pytest.approx((1 + 4 / 5) / 2)
    assert summary["slot_action"] == 0.5
    assert summary["slot_colour"] == 1.0
    assert summary["word_accuracy"] == pytest.approx((1 + 3 / 4) / 2)


SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def test_pairwise_distances_of_a_square() -> None:
    d = pairwise_distances(SQUARE)
    np.testing.assert_allclose(sorted(d), [1, 1, 1, 1, math.sqrt(2), math.sqrt(2)])
    assert d_avg(SQUARE) == pytest.approx((4 + 2 * math.sqrt(2)) / 6)


def test_d_rel_of_four_points_on_a_square_is_0_9863() -> None:
    assert round(d_rel(SQUARE), 4) == 0.9863  # paper note 5
    assert d_rel(SQUARE * 7.0 + 3.0) == pytest.approx(d_rel(SQUARE))


def test_d_rel_of_equidistant_points_is_one() -> None:
    tetrahedron = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    assert d_rel(tetrahedron) == pytest.approx(1.0, abs=1e-12)
    assert d_rel(np.eye(5)) == pytest.approx(1.0, abs=1e-12)


def test_d_rel_is_zero_when_two_patterns_coincide() -> None:
    assert d_rel([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]]) == 0.0
    assert d_rel([[0.5, 0.5], [0.5, 0.5]]) == 0.0


def test_distance_measures_reject_a_single_pattern() -> None:
    with pytest.raises(ValueError, match="at least 2"):
        d_avg([[1.0, 2.0]])


def test_d_inter_is_within_cluster_and_d_intra_between_centroids() -> None:
    points = [[0, 0], [2, 0], [0, 4], [0, 6], [0, 8]]
    labels = ["pull", "pull", "push", "push", "push"]
    # pull: one pair at distance 2; push: pairs 2, 4, 2 -> 8/3
    assert d_inter(points, labels) == pytest.approx((2 + 8 / 3) / 2)
    # centroids (1, 0) and (0, 6)
    assert d_intra(points, labels) == pytest.approx(math.sqrt(37))
    with pytest.raises(ValueError, match="2 clusters"):
        d_intra(points, ["a"] * 5)
    with pytest.raises(ValueError, match="every cluster"):
        d_inter(points, ["a", "a", "a", "a", "b"])


def _patterns(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(16, 5)) @ np.diag([3.0, 2.0, 1.0, 0.5, 0.1])


def test_pca_is_deterministic_under_sign_flips_and_row_order() -> None:
    x = _patterns(0)
    a = CscPCA(2).fit(x)
    b = CscPCA(2).fit(-x)
    c = CscPCA(2).fit(x[::-1])
    np.testing.assert_allclose(a.components_, b.components_, atol=1e-12)
    np.testing.assert_allclose(a.components_, c.components_, atol=1e-12)
    largest = np.abs(a.components_).argmax(axis=1)
    assert np.all(a.components_[np.arange(2), largest] > 0)
    assert a.explained_variance_ratio_[0] > a.explained_variance_ratio_[1] > 0


def test_pca_inverse_transform_recovers_full_rank_patterns() -> None:
    x = _patterns(1)
    pca = CscPCA(5)
    z = pca.fit_transform(x)
    assert pca.explained_variance_ratio_.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(pca.inverse_transform(z), x, atol=1e-10)
    with pytest.raises(ValueError, match="n_components"):
        CscPCA(6).fit(x)
    with pytest.raises(RuntimeError, match="fit"):
        CscPCA(2).transform(x)
