"""Evaluation: scores per split, one deterministic run on the paper's split and on another one."""

from __future__ import annotations

import json

import pytest

from model import checkpoint
from model.data import scene_key
from model.experiments.evaluation import run_once, score
from model.experiments.splits import scene_split
from model.training import train
from tests.model.tiny_corpus import tiny_config, tiny_corpus


def test_scene_key_strips_the_variant():
    assert scene_key("slide-red-apple-2") == "slide-red-apple"
    assert scene_key("show-me-blue-dice-13") == "show-me-blue-dice"
    assert scene_key("show-me-blue-dice") == "show-me-blue-dice"


def test_score_reports_every_measure_per_space():
    data = tiny_corpus(variants=2)
    trained = train(data, "faithful", tiny_config(epochs=2), seed=0)
    result = score(trained.model, data, trained.lexicon)
    for key in (
        "sentence_exact",
        "f1",
        "precision",
        "recall",
        "edit_distance",
        "word_accuracy",
        "slot_action",
    ):
        assert 0.0 <= result[key] <= max(1.0, result["edit_distance"])
    assert result["n"] == len(data)
    for space in ("somatosensory", "visual", "auditory"):
        measures = result["csc"][space]
        assert set(measures) == {"d_avg", "d_rel", "d_inter", "d_intra"}
        assert all(isinstance(v, float) for v in measures.values())


def test_run_once_is_deterministic_json_and_saves_a_checkpoint(tmp_path):
    data = tiny_corpus(variants=2)
    a = run_once(
        data, "faithful", fold=1, seed=0, config=tiny_config(epochs=2).to_dict(), out_dir=tmp_path / "ck"
    )
    b = run_once(data, "faithful", fold=1, seed=0, config=tiny_config(epochs=2))
    assert json.dumps(a.metrics, sort_keys=True) == json.dumps(b.metrics, sort_keys=True)
    assert set(a.metrics) == {"train", "test", "mixed"}
    assert a.metrics["mixed"]["f1"] == pytest.approx((a.metrics["train"]["f1"] + a.metrics["test"]["f1"]) / 2)
    _, meta = checkpoint.load(tmp_path / "ck")
    assert meta["fold"] == 1 and meta["metrics"]["test"]["n"] == len(meta["split"]["test"]) == 12
    assert not {scene_key(i) for i in meta["split"]["train"]} & {scene_key(i) for i in meta["split"]["test"]}
    assert meta["split_kind"] == "scenes" and meta["train_scenes"] is None
    _, test_idx = scene_split(data.ids, 1)
    assert meta["split"]["test"] == [data.ids[i] for i in test_idx]


def test_run_once_on_the_size_split_trains_on_so_many_scenes_and_says_so(tmp_path):
    data = tiny_corpus(variants=2)  # 12 scenes: 3 tested, 2 of the other 9 trained on
    run = run_once(
        data, "faithful", 0, 0, tiny_config(epochs=1), tmp_path / "ck", split="size", train_scenes=2
    )
    _, meta = checkpoint.load(tmp_path / "ck")
    assert meta["split_kind"] == "size" and meta["train_scenes"] == 2
    assert len({scene_key(i) for i in meta["split"]["train"]}) == 2 and run.metrics["train"]["n"] == 4
    assert len({scene_key(i) for i in meta["split"]["test"]}) == 3 and run.metrics["test"]["n"] == 6


def test_run_once_refuses_a_size_split_without_its_size_before_training():
    with pytest.raises(ValueError, match="train_scenes"):
        run_once(tiny_corpus(variants=1), "faithful", 0, 0, tiny_config(epochs=10_000), split="size")
