"""Evaluation: the 50:50 split by scene, scores per split, one deterministic run."""

from __future__ import annotations

import json

import pytest

from model import checkpoint
from model.data import scene_key
from model.experiments.evaluation import fold_split, run_once, score
from model.training import train
from tests.model.tiny_corpus import tiny_config, tiny_corpus

IDS = [
    f"{a}-{c}-{o}-{k}"
    for a in ("pull", "show-me")
    for c in ("red", "blue")
    for o in ("apple", "dice")
    for k in range(4)
]


def test_scene_key_strips_the_variant():
    assert scene_key("slide-red-apple-2") == "slide-red-apple"
    assert scene_key("show-me-blue-dice-13") == "show-me-blue-dice"
    assert scene_key("show-me-blue-dice") == "show-me-blue-dice"


@pytest.mark.parametrize("fold", [0, 1, 7])
def test_fold_split_keeps_scenes_whole_and_halves_them(fold):
    train_idx, test_idx = fold_split(IDS, fold)
    assert sorted(train_idx + test_idx) == list(range(len(IDS)))
    train_scenes = {scene_key(IDS[i]) for i in train_idx}
    test_scenes = {scene_key(IDS[i]) for i in test_idx}
    assert not train_scenes & test_scenes
    assert len(train_scenes) == len(test_scenes) == 4
    assert train_idx == sorted(train_idx)


def test_fold_split_is_seeded_per_fold():
    assert fold_split(IDS, 3, seed=1) == fold_split(IDS, 3, seed=1)
    splits = {tuple(fold_split(IDS, k)[0]) for k in range(10)}
    assert len(splits) > 5
    assert fold_split(IDS, 0, seed=0) != fold_split(IDS, 0, seed=1) or fold_split(
        IDS, 1, seed=0
    ) != fold_split(IDS, 1, seed=1)


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
