"""MultiMTRNN (eqs. 16-17): abstraction of perception, cell assemblies, description of a scene."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from model.assemblies import ASSEMBLIES, CellAssemblies
from model.config import MTRNNConfig
from model.encoding.utterance import PHONEMES, Lexicon
from model.mtrnn import scaled_logistic
from model.multimtrnn import Description, MultiMTRNN, pad_sequences, somatosensory_inputs, visual_inputs
from tests.model.tiny_corpus import tiny_config, tiny_corpus


@pytest.fixture(scope="module")
def model() -> MultiMTRNN:
    config = tiny_config()
    config.generation_steps = 40
    return MultiMTRNN(config, seed=0)


@pytest.fixture(scope="module")
def lexicon() -> Lexicon:
    return Lexicon.from_sentences(tiny_corpus().utterances)


def test_cell_assemblies_are_eq17_on_the_activity_of_the_perception_csc():
    ca = CellAssemblies(csc_s=2, csc_v=3, csc_a=4, seed=1)
    c_s, c_v = torch.randn(5, 2), torch.randn(5, 3)
    w, b = ca.weight.detach(), ca.bias.detach()
    expected = scaled_logistic(c_s) @ w[:, :2].T + scaled_logistic(c_v) @ w[:, 2:].T + b
    assert torch.allclose(ca(c_s, c_v), expected, atol=1e-6)
    assert ASSEMBLIES["linear"] is CellAssemblies
    assert CellAssemblies(**ca.init_kwargs()).weight.equal(ca.weight)


def test_padding_after_a_sequence_does_not_change_its_abstraction(model):
    data = tiny_corpus()
    c_s, c_v = model.abstract(data.proprioception[:3], data.vision[:3])
    alone = [model.abstract([p], [v]) for p, v in zip(data.proprioception[:3], data.vision[:3], strict=True)]
    assert torch.allclose(c_s, torch.cat([a[0] for a in alone]), atol=1e-6)
    assert torch.allclose(c_v, torch.cat([a[1] for a in alone]), atol=1e-6)
    assert c_s.shape == (3, model.config.somatosensory.csc) and c_v.shape == (3, model.config.visual.csc)


def test_vision_uses_only_the_configured_feature_columns(model):
    data = tiny_corpus()
    v21 = data.vision[0]
    v19 = v21[:, :19]
    changed = v21.copy()
    changed[:, 19:] = 123.0  # the centroid columns
    assert torch.equal(
        model.abstract([data.proprioception[0]], [v19])[1],
        model.abstract([data.proprioception[0]], [changed])[1],
    )
    padded, lengths = pad_sequences([v21, v21[:5]], 19)
    assert padded.shape == (2, len(v21), 19) and lengths.tolist() == [len(v21), 5]
    with pytest.raises(ValueError, match="features"):
        pad_sequences([v21[:, :10]], 19)


def test_object_motion_reads_where_the_object_moved_not_where_it_lies():
    config = tiny_config()
    config.visual = MTRNNConfig(io=21, cf=6, cs=4, tau_io=2, tau_cf=5, tau_cs=16)
    config.object_motion = "visual"
    rng = np.random.default_rng(0)
    a, b = rng.random((9, 21)).astype(np.float32), rng.random((6, 21)).astype(np.float32)
    moved, lengths = visual_inputs([a, b], config)
    assert moved.shape == (2, 9, 21) and lengths.tolist() == [9, 6]
    np.testing.assert_allclose(moved[0, :, :19], a[:, :19])  # the paper's 19 features as they are
    np.testing.assert_allclose(moved[0, :, 19:], a[:, 19:] - a[0, 19:], atol=1e-6)
    assert torch.all(moved[0, 0, 19:] == 0) and torch.all(moved[1, 6:] == 0)  # starts at 0; padding stays 0
    elsewhere = a.copy()
    elsewhere[:, 19:] += np.float32(0.2)  # the same motion in another part of the frame
    assert torch.allclose(visual_inputs([elsewhere], config)[0], moved[:1], atol=1e-6)
    net = MultiMTRNN(config, seed=0)
    proprioception = tiny_corpus().proprioception[0][:9]
    c_v = net.abstract([proprioception], [a])[1]
    assert torch.allclose(c_v, net.abstract([proprioception], [elsewhere])[1])
    config.visual = MTRNNConfig(io=19, cf=6, cs=4, tau_io=2, tau_cf=5, tau_cs=16)
    with pytest.raises(ValueError, match="object_motion 'visual' needs"):
        config.__post_init__()


def test_mtrnn_s_can_read_the_object_motion_beside_the_arm():
    config = tiny_config()
    config.somatosensory = MTRNNConfig(io=7, cf=6, cs=4, tau_io=2, tau_cf=5, tau_cs=50)
    config.object_motion = "somatosensory"
    data = tiny_corpus()
    p, v = data.proprioception[:2], data.vision[:2]
    inputs, lengths = somatosensory_inputs(p, config, vision=v)
    assert inputs.shape == (2, max(len(x) for x in p), 7) and lengths.tolist() == [len(x) for x in p]
    np.testing.assert_allclose(inputs[0, : len(p[0]), :5], p[0])
    np.testing.assert_allclose(inputs[0, : len(p[0]), 5:], v[0][:, 19:] - v[0][0, 19:], atol=1e-6)
    net = MultiMTRNN(config, seed=0)
    still = [x.copy() for x in v]
    still[0][:, 19:] = still[0][0, 19:]  # the object does not move: only MTRNN_s's reading changes
    (c_s, c_v), (c_s_still, c_v_still) = net.abstract(p, v), net.abstract(p, still)
    assert not torch.allclose(c_s[0], c_s_still[0]) and torch.allclose(c_s[1], c_s_still[1])
    assert torch.equal(c_v, c_v_still)  # this MTRNN_v reads the paper's 19 features
    with pytest.raises(ValueError, match="needs the vision features"):
        somatosensory_inputs(p, config)
    with pytest.raises(ValueError, match="one time grid"):
        somatosensory_inputs(p[:1], config, vision=[v[0][:-2]])
    config.object_motion = "elsewhere"
    with pytest.raises(ValueError, match="object_motion must be one of"):
        config.__post_init__()


def test_describe_returns_text_and_every_csc(model, lexicon):
    data = tiny_corpus()
    d = model.describe(data.proprioception[0], data.vision[0], lexicon)
    assert isinstance(d, Description)
    assert d.activity.shape == (40, len(PHONEMES))
    assert np.allclose(d.activity.sum(axis=1), 1.0, atol=1e-5)
    assert d.csc_s.shape == (2,) and d.csc_v.shape == (2,) and d.csc_a.shape == (3,)  # ceil(|Cs| / 2)
    assert isinstance(d.text, str) and all(w in lexicon.words or w in ".!?" for w in d.words)
    batch = model.describe_batch(data.proprioception[:2], data.vision[:2], lexicon)
    assert np.allclose(batch[0].activity, d.activity, atol=1e-6) and batch[0].text == d.text


def test_generate_from_csc_is_the_generator_alone(model, lexicon):
    data = tiny_corpus()
    d = model.describe(data.proprioception[0], data.vision[0], lexicon)
    again = model.generate_from_csc(d.csc_a, lexicon)
    assert np.allclose(again.activity, d.activity, atol=1e-6) and again.csc_s is None
    with pytest.raises(ValueError, match="values"):
        model.generate_from_csc([0.0, 1.0], lexicon)


def test_activity_trace_covers_every_layer_of_the_three_nets(model, lexicon):
    data = tiny_corpus()
    p, v = data.proprioception[0], data.vision[0]
    trace = model.activity_trace(p, v, lexicon)
    assert trace.somatosensory.io.shape == (len(p), 5) and trace.somatosensory.cf.shape == (len(p), 6)
    assert trace.visual.cs.shape == (len(v), 4) and trace.visual.csc.shape == (len(v), 2)
    assert trace.auditory.io.shape == (40, len(PHONEMES)) and trace.auditory.csc.shape == (40, 3)
    assert np.allclose(trace.somatosensory.csc[-1], trace.description.csc_s, atol=1e-6)
    assert np.allclose(trace.auditory.csc[0], trace.description.csc_a, atol=1e-6)
    assert np.allclose(trace.auditory.io, trace.description.activity, atol=1e-6)
