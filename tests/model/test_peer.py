"""The peer baseline: a PRAE-style GRU encoder-decoder that describes scenes like the MultiMTRNN."""

from __future__ import annotations

import numpy as np
import pytest
from tiny_data import tiny_sequence_set

from model.evaluation import fold_split
from model.multimtrnn import Description
from model.peer import PeerConfig, load, run_once, save, train_peer
from model.training import MODES

FAST = PeerConfig(hidden=32, epochs=20, progress_every=10).to_dict()


@pytest.mark.slow
def test_the_peer_learns_its_training_sentences_and_reports_progress() -> None:
    data = tiny_sequence_set()
    events: list[dict] = []
    trained = train_peer(data, {**FAST, "hidden": 64, "epochs": 150}, seed=0, progress=events.append)
    assert [e["epoch"] for e in events] == list(range(10, 151, 10))
    assert events[-1]["loss"] < events[0]["loss"] / 2
    assert len(events[-1]["csc"]) == len(data) and len(events[-1]["csc"][0]) == 12
    described = trained.model.describe_batch(data.proprioception, data.vision, trained.lexicon)
    assert all(isinstance(d, Description) for d in described)
    assert described[0].csc_s.shape == described[0].csc_v.shape == described[0].csc_a.shape == (12,)
    exact = np.mean([d.text == u for d, u in zip(described, data.utterances, strict=True)])
    assert exact >= 0.9  # 150 Adam epochs on 16 recordings of 8 scenes (measured: 1.0)


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
    train_idx, test_idx = fold_split(data.ids, 1, seed=0)
    assert result.meta["split"]["test"] == [data.ids[i] for i in test_idx]
    assert set(result.metrics) == {"train", "test", "mixed"}
    for key in ("sentence_exact", "f1", "edit_distance", "word_accuracy", "slot_object", "csc"):
        assert key in result.metrics["test"]
    assert result.metrics["mixed"]["f1"] == (result.metrics["train"]["f1"] + result.metrics["test"]["f1"]) / 2
    assert (tmp_path / "ckpt" / "meta.json").is_file()


def test_peer_is_a_registered_training_mode() -> None:
    assert "peer" in MODES
