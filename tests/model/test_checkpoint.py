"""Checkpoints: safetensors + JSON, atomic, no pickle, identical generation after a round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from model import checkpoint
from model.training import train
from tests.model.tiny_corpus import tiny_config, tiny_corpus


@pytest.fixture(scope="module")
def trained():
    return train(tiny_corpus(variants=1), "faithful", tiny_config(epochs=3), seed=2)


def test_round_trip_generates_identical_output(trained, tmp_path):
    data = tiny_corpus(variants=1)
    out = checkpoint.save(
        trained.model, tmp_path / "ck", {**trained.meta, "metrics": {"f1": np.float64(0.5)}}, trained.csc
    )
    model, meta = checkpoint.load(out)
    lexicon = trained.lexicon
    before = trained.model.describe_batch(data.proprioception, data.vision, lexicon)
    after = model.describe_batch(data.proprioception, data.vision, lexicon)
    for a, b in zip(before, after, strict=True):
        assert np.array_equal(a.activity, b.activity) and a.text == b.text
    assert meta["mode"] == "faithful" and meta["seed"] == 2 and meta["metrics"] == {"f1": 0.5}
    assert meta["generation_steps"] == model.config.generation_steps == trained.model.config.generation_steps
    assert meta["assemblies"]["kind"] == "linear" and meta["lexicon"] == list(lexicon.words)
    tables = checkpoint.load_training_csc(out)
    assert np.array_equal(tables["auditory_c0"], trained.csc["auditory_c0"])


def test_checkpoint_is_safetensors_and_json_only(trained, tmp_path):
    out = checkpoint.save(trained.model, tmp_path / "ck", trained.meta)
    assert sorted(p.name for p in out.iterdir()) == ["meta.json", "model.safetensors"]
    json.loads((out / "meta.json").read_text())
    assert checkpoint.load_training_csc(out) == {}
    with open(out / "model.safetensors", "rb") as fh:  # safetensors: 8-byte header length, then JSON
        n = int.from_bytes(fh.read(8), "little")
        assert json.loads(fh.read(n))


def test_saving_over_a_checkpoint_replaces_it_whole(trained, tmp_path):
    target = tmp_path / "ck"
    checkpoint.save(trained.model, target, trained.meta, trained.csc)
    checkpoint.save(trained.model, target, {"note": "second"})
    assert json.loads((target / "meta.json").read_text())["note"] == "second"
    assert not (target / "training_csc.safetensors").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["ck"]  # no temporary directories left behind


def test_loading_rebuilds_the_same_weights(trained, tmp_path):
    model, _ = checkpoint.load(checkpoint.save(trained.model, tmp_path / "ck", trained.meta))
    for name, value in trained.model.state_dict().items():
        assert torch.equal(model.state_dict()[name], value), name


def test_familiarity_is_fitted_by_train_and_saved_beside_the_model(trained, tmp_path):
    data = tiny_corpus(variants=1)
    assert trained.familiarity is not None
    out = checkpoint.save(trained.model, tmp_path / "ck", trained.meta, trained.csc, trained.familiarity)
    assert (out / "familiarity.safetensors").is_file()
    again = checkpoint.load_familiarity(out)
    for p, v in zip(data.proprioception, data.vision, strict=True):
        assert again.score(p, v) == trained.familiarity.score(p, v) == {"proprioception": 1.0, "vision": 1.0}
    assert checkpoint.load_familiarity(checkpoint.save(trained.model, tmp_path / "old", trained.meta)) is None
