"""Lesson 7 on the objects split: the lesson lists the models trained on it (from their meta) and,
for one of them, the grid of its held-out objects with the colour and shape words it said."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from data.scenario import all_scenes, recording_id
from model import checkpoint
from model.encoding.utterance import Lexicon
from model.experiments.splits import held_out_pairs, split_indices
from model.multimtrnn import MultiMTRNN
from tests.app_builder import build_app, lesson_world
from tests.server.lesson_world import VARIANTS

IDS = [recording_id(s, v) for s in all_scenes() for v in VARIANTS]
TEXTS = [s.utterance for s in all_scenes() for _ in VARIANTS]


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    settings, load = lesson_world(tmp_path_factory.mktemp("world"))
    return settings, load


def _client(world: tuple) -> TestClient:
    return TestClient(build_app(*world))


def _save_objects_model(root: Path, fold: int) -> None:
    """An (untrained) model whose meta says it was trained on fold `fold` of the objects split."""
    train, test = split_indices(IDS, TEXTS, fold, "objects")
    lexicon = list(Lexicon.from_sentences([s.utterance for s in all_scenes()]).words)
    meta = {
        "mode": "end_to_end",
        "lexicon": lexicon,
        "fold": fold,
        "split_kind": "objects",
        "train_scenes": None,
        "split": {"train": [IDS[i] for i in train], "test": [IDS[i] for i in test]},
    }
    checkpoint.save(MultiMTRNN(seed=3), root / "models" / f"objects-{fold}", meta)


def test_without_a_model_of_the_objects_split_the_lesson_says_none_exists(world) -> None:
    with _client(world) as client:
        body = client.get("/api/lessons/generalising", params={"model": "faithful"}).json()
    assert body["split"] == "scenes" and body["held_out"] == [] and body["objects_models"] == []


def test_a_model_of_the_objects_split_shows_what_it_said_for_each_held_out_object(world) -> None:
    settings, _ = world
    _save_objects_model(settings.user_dir, 1)
    with _client(world) as client:
        listed = client.get("/api/lessons/generalising", params={"model": "faithful"}).json()[
            "objects_models"
        ]
        body = client.get("/api/lessons/generalising", params={"model": "objects-1"}).json()
    assert listed == [{"name": "objects-1", "mode": "end_to_end", "fold": 1}]
    assert body["split"] == "objects" and body["fold"] == 1
    grid = body["held_out"]
    assert [(g["colour"], g["shape"]) for g in grid] == held_out_pairs(TEXTS, 1, ("colour", "object"))
    for g in grid:  # 4 actions x 2 recordings of each held-out object
        assert g["recordings"] == 8 == sum(g["colour_said"].values()) == sum(g["shape_said"].values())
        assert g["colour_right"] == g["colour_said"].get(g["colour"], 0) / 8
        assert g["shape_right"] == g["shape_said"].get(g["shape"], 0) / 8
    novel = [s for s in body["scenes"] if s["split"] == "test"]
    assert len(novel) == 16 and not any(s["seen"]["object"] for s in novel)
    assert json.dumps(body, allow_nan=False)
