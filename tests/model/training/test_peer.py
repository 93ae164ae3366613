"""The peer baseline: a PRAE-style GRU encoder-decoder that describes scenes like the MultiMTRNN."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from safetensors.torch import load_file, save_file

from model.checkpoint import load, save
from model.experiments.evaluation import run_once
from model.experiments.splits import scene_split
from model.multimtrnn import Description
from model.training import MODES
from model.training.peer import LEGACY, PeerConfig, PeerModel, train_peer
from tests.model.tiny_data import tiny_sequence_set

FAST = PeerConfig(hidden=32, epochs=20, progress_every=10).to_dict()


@pytest.mark.slow
def test_the_peer_learns_its_training_sentences_and_reports_progress() -> None:
    data = tiny_sequence_set()
    events: list[dict] = []
    config = {**FAST, "hidden": 64, "epochs": 150, "batch": 4, "lr": 1e-2}  # 4 Adam steps per epoch
    trained = train_peer(data, config, seed=0, progress=events.append)
    assert [e["epoch"] for e in events] == list(range(10, 151, 10))
    assert events[-1]["loss"] < events[0]["loss"] / 2
    assert len(events[-1]["csc"]) == len(data) and len(events[-1]["csc"][0]) == 12
    described = trained.model.describe_batch(data.proprioception, data.vision, trained.lexicon)
    assert all(isinstance(d, Description) for d in described)
    assert described[0].csc_s.shape == described[0].csc_v.shape == described[0].csc_a.shape == (12,)
    exact = np.mean([d.text == u for d, u in zip(described, data.utterances, strict=True)])
    assert exact >= 0.9  # 150 epochs closed-loop on 16 recordings of 8 scenes (measured: 1.0)


@pytest.mark.slow
def test_training_is_deterministic_and_checkpoints_round_trip(tmp_path) -> None:
    data = tiny_sequence_set()
    a = train_peer(data, FAST, seed=3)
    b = train_peer(data, FAST, seed=3)
    for (k, va), (_, vb) in zip(a.model.state_dict().items(), b.model.state_dict().items(), strict=True):
        assert np.array_equal(va.numpy(), vb.numpy()), k
    save(a.model, tmp_path / "peer", a.meta)
    model, meta = load(tmp_path / "peer")
    before = a.model.describe_batch(data.proprioception, data.vision, a.lexicon)
    after = model.describe_batch(data.proprioception, data.vision, a.lexicon)
    assert meta["mode"] == "peer"
    assert [d.text for d in before] == [d.text for d in after]
    assert np.allclose(before[0].activity, after[0].activity)
    assert not any(p.suffix == ".pt" or p.suffix == ".pkl" for p in (tmp_path / "peer").iterdir())


@pytest.mark.slow
def test_the_peer_uses_the_same_folds_and_metrics_as_the_multimtrnn(tmp_path) -> None:
    data = tiny_sequence_set()
    result = run_once(data, "peer", fold=1, seed=0, config=FAST, out_dir=tmp_path / "ckpt")
    train_idx, test_idx = scene_split(data.ids, 1)
    assert result.meta["split"]["test"] == [data.ids[i] for i in test_idx]
    assert set(result.metrics) == {"train", "test", "mixed"}
    for key in ("sentence_exact", "f1", "edit_distance", "word_accuracy", "slot_object", "csc"):
        assert key in result.metrics["test"]
    assert result.metrics["mixed"]["f1"] == (result.metrics["train"]["f1"] + result.metrics["test"]["f1"]) / 2
    assert (tmp_path / "ckpt" / "meta.json").is_file()


def test_peer_is_a_registered_training_mode() -> None:
    assert "peer" in MODES


def test_the_encoders_are_fed_inputs_standardised_by_the_training_set() -> None:
    data = tiny_sequence_set()
    trained = train_peer(data, {**FAST, "epochs": 1}, seed=0)
    prop = np.concatenate(data.proprioception)
    vis = np.concatenate(data.vision)[:, :19]
    for encoder, x in ((trained.model.somatosensory, prop), (trained.model.visual, vis)):
        assert np.allclose(encoder.mean.numpy(), x.mean(axis=0), atol=1e-5)
        assert np.allclose(encoder.std.numpy(), np.maximum(x.std(axis=0, ddof=1), 1e-3), rtol=1e-4)
    assert "visual.mean" in trained.model.state_dict()  # kept in the safetensors checkpoint


def test_the_encoders_read_every_stride_th_step_only() -> None:
    model = PeerModel(PeerConfig(stride=4), generation_steps=20, seed=0)
    prop = torch.rand(1, 12, 5)
    vis = torch.rand(1, 12, 19)
    lengths = torch.tensor([12])
    with torch.no_grad():
        before = model.perceive(prop, lengths, vis, lengths)[2]
        off, on = prop.clone(), prop.clone()
        off[0, 1] += 1.0  # step 1 is skipped
        on[0, 4] += 1.0  # step 4 is read
        assert torch.equal(model.perceive(off, lengths, vis, lengths)[2], before)
        assert not torch.equal(model.perceive(on, lengths, vis, lengths)[2], before)


def test_a_checkpoint_from_before_the_training_options_loads_as_it_was_trained(tmp_path) -> None:
    data = tiny_sequence_set()
    trained = train_peer(data, {**FAST, "epochs": 2, "stride": 1, "normalise": False}, seed=1)
    save(trained.model, tmp_path / "old", trained.meta)
    meta = json.loads((tmp_path / "old" / "meta.json").read_text())
    for key in LEGACY:
        del meta["peer_config"][key]  # as written by the full-batch, raw-input peer
    (tmp_path / "old" / "meta.json").write_text(json.dumps(meta))
    weights = load_file(str(tmp_path / "old" / "model.safetensors"))
    legacy_weights = {k: v for k, v in weights.items() if not k.endswith((".mean", ".std"))}
    save_file(legacy_weights, str(tmp_path / "old" / "model.safetensors"))
    model, _ = load(tmp_path / "old")
    assert model.config.stride == 1 and not model.config.normalise
    before = trained.model.describe_batch(data.proprioception, data.vision, trained.lexicon)
    after = model.describe_batch(data.proprioception, data.vision, trained.lexicon)
    assert np.allclose(before[0].activity, after[0].activity)
