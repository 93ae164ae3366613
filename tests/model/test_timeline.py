"""MultiMTRNN.timeline: what the model would say if asked at every step of a recording (issue 15)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from data.corpus import load_corpus
from model import checkpoint
from model.assemblies import WordAssemblies
from model.encoding.utterance import Lexicon
from model.multimtrnn import MultiMTRNN, settle_step, word_settles
from tests.model.tiny_corpus import tiny_config, tiny_corpus

MODELS = Path(__file__).resolve().parents[2] / "data" / "artefacts" / "models"
SLOTS = [["pull", "push", "slide"], ["blue", "red"], ["apple", "dice"]]


@pytest.fixture(scope="module")
def lexicon() -> Lexicon:
    return Lexicon.from_sentences(tiny_corpus().utterances)


def tiny_model(words: bool) -> MultiMTRNN:
    config = tiny_config()
    config.generation_steps = 40
    if not words:
        return MultiMTRNN(config, seed=0)
    s, v, a = config.somatosensory.csc, config.visual.csc, config.auditory.csc
    return MultiMTRNN(config, assemblies=WordAssemblies(s, v, a, SLOTS, weight_init=1.0, seed=3), seed=0)


def test_a_settle_is_one_past_the_last_step_it_did_not_hold() -> None:
    assert settle_step([True, True, True]) == 0
    assert settle_step([False, True, True]) == 1
    assert settle_step([True, False, True, True]) == 2
    assert settle_step([True, False]) == 2


def test_words_settle_by_alignment_so_a_longer_action_does_not_shift_the_others() -> None:
    said = [
        ["show", "me", "the", "red", "apple"],
        ["slide", "the", "blue", "apple"],
        ["slide", "the", "red", "apple"],
    ]
    assert word_settles(said) == [1, 0, 2, 0]  # slide, the, red, apple


@pytest.mark.parametrize("words", [False, True])
def test_timeline_has_one_entry_per_step_and_ends_on_the_description(words: bool, lexicon: Lexicon) -> None:
    model, data = tiny_model(words), tiny_corpus()
    prop, vis = data.proprioception[0], data.vision[0]
    tl = model.timeline(prop, vis, lexicon)
    steps = len(prop)
    assert len(tl.texts) == len(tl.words) == steps and tl.csc_a.shape == (steps, model.config.auditory.csc)
    d = model.describe(prop, vis, lexicon)
    assert tl.texts[-1] == d.text and tl.words[-1] == d.words
    assert np.array_equal(tl.csc_a[-1], d.csc_a)
    assert len(tl.word_settles) == len(d.words)
    assert all(0 <= s < steps for s in tl.word_settles)
    if not words:
        assert tl.slots == [] and tl.slot_probabilities == [] and tl.slot_settles == []
        return
    assert tl.slots == SLOTS and len(tl.slot_settles) == len(SLOTS)
    for phrases, p, settle in zip(SLOTS, tl.slot_probabilities, tl.slot_settles, strict=True):
        assert p.shape == (steps, len(phrases))
        assert np.allclose(p.sum(axis=1), 1.0, atol=1e-5)  # a softmax within the slot
        winners = p.argmax(axis=1)
        assert (winners[settle:] == winners[-1]).all() and (settle == 0 or winners[settle - 1] != winners[-1])


def test_the_csc_trajectory_at_step_t_is_the_abstraction_of_the_recording_read_up_to_t() -> None:
    model, data = tiny_model(False), tiny_corpus()
    prop, vis = data.proprioception[1], data.vision[1]
    c_s, c_v = model.csc_trajectories(prop, vis)
    with torch.no_grad():
        for t in (0, 4, len(prop) - 1):
            s_t, v_t = model.abstract([prop[: t + 1]], [vis[: t + 1]])
            assert torch.allclose(c_s[t], s_t[0], atol=1e-6) and torch.allclose(c_v[t], v_t[0], atol=1e-6)


def test_a_timeline_needs_both_senses_on_one_time_grid(lexicon: Lexicon) -> None:
    data = tiny_corpus()
    with pytest.raises(ValueError, match="one time grid"):
        tiny_model(False).timeline(data.proprioception[0], data.vision[0][:-1], lexicon)


@pytest.mark.parametrize("name", ["default", "faithful"])
def test_each_step_of_a_shipped_models_timeline_is_what_it_says_of_the_recording_cut_there(name: str) -> None:
    model, meta = checkpoint.load(MODELS / name)
    lexicon = Lexicon(meta["lexicon"])
    corpus = load_corpus()
    for rid in ("slide-red-apple-2", "show-me-green-banana-2"):
        e = corpus.by_id(rid)
        tl = model.timeline(e.proprioception, e.vision, lexicon)
        assert len(tl.texts) == len(e.proprioception)
        assert tl.texts[-1] == model.describe(e.proprioception, e.vision, lexicon).text
        for t in range(0, len(tl.texts), 7):
            assert tl.texts[t] == model.describe(e.proprioception[: t + 1], e.vision[: t + 1], lexicon).text
