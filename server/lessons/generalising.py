"""Lesson 7, generalising: how one model describes every scene, training vs novel scenes, and for
novel scenes whether their object and action pairings were ever seen in training.

For a model trained on the `objects` split (`model.experiments.splits`: four colour x shape objects
held out per fold, its meta's `split_kind`), the grid of its held-out objects: which colour word
and which shape word it said for each. The models trained on that split are listed
(`objects_models`), so that the lesson uses one that exists, or offers to train one."""

from __future__ import annotations

from collections import Counter

from data.scenario import ACTIONS, COLOURS, SHAPES
from model.metrics import parse_slots, sentence_exact
from server.services.corpus import Corpus
from server.services.models import LoadedModel, ModelRegistry
from server.services.survey import SurveyService

SLOTS = ("action", "colour", "object")


def _scenes(corpus: Corpus, lm: LoadedModel, ids: list[str], texts: list[str]) -> dict[str, dict]:
    """Per scene: its slots, its split and what the model said for each of its recordings."""
    scenes: dict[str, dict] = {}
    for rid, text in zip(ids, texts, strict=True):
        e = corpus.entries[rid]
        s = scenes.setdefault(
            e.scene.id,
            {
                "scene": e.scene.id,
                "action": e.scene.action,
                "colour": e.scene.colour,
                "shape": e.scene.shape,
                "expected": e.utterance,
                "split": lm.split_of(rid, e.scene.id),
                "recordings": [],
            },
        )
        got = parse_slots(text, ACTIONS, COLOURS, SHAPES)
        target = {"action": e.scene.action, "colour": e.scene.colour, "object": e.scene.shape}
        wrong = [k for k in target if got[k] != target[k]]
        s["recordings"].append(
            {"id": rid, "said": text, "exact": sentence_exact(text, e.utterance), "wrong": wrong}
        )
    return scenes


def _score(scenes: list[dict], trained: list[dict]) -> None:
    """Each scene's exact share and wrong slots, and which of its pairings training has seen."""
    seen_objects = {(s["colour"], s["shape"]) for s in trained}
    seen_action_colour = {(s["action"], s["colour"]) for s in trained}
    seen_action_shape = {(s["action"], s["shape"]) for s in trained}
    for s in scenes:
        recs = s["recordings"]
        s["exact"] = round(sum(r["exact"] for r in recs) / len(recs), 4)
        s["wrong_slots"] = {k: sum(k in r["wrong"] for r in recs) for k in SLOTS}
        s["seen"] = {
            "object": (s["colour"], s["shape"]) in seen_objects,
            "action_with_colour": (s["action"], s["colour"]) in seen_action_colour,
            "action_with_shape": (s["action"], s["shape"]) in seen_action_shape,
        }


def summary(group: list[dict]) -> dict:
    """Exact sentences and slot errors over every recording of a group of scenes."""
    recs = [r for s in group for r in s["recordings"]]
    if not recs:
        return {"recordings": 0}
    return {
        "recordings": len(recs),
        "exact": round(sum(r["exact"] for r in recs) / len(recs), 4),
        "slot_errors": {k: round(sum(k in r["wrong"] for r in recs) / len(recs), 4) for k in SLOTS},
    }


def objects_models(models: ModelRegistry) -> list[dict]:
    """The models trained on the objects split: name, mode and fold (from their meta.json)."""
    return [
        {"name": name, "mode": str(meta.get("mode", "unknown")), "fold": meta.get("fold")}
        for name, meta in models.metas().items()
        if meta.get("split_kind") == "objects"
    ]


def held_out(novel: list[dict]) -> list[dict]:
    """Per held-out object (colour x shape): its recordings, how often each colour word and each
    shape word was said for it ("" = none), and the shares right."""
    grid = []
    for colour, shape in sorted({(s["colour"], s["shape"]) for s in novel}):
        recs = [r for s in novel if (s["colour"], s["shape"]) == (colour, shape) for r in s["recordings"]]
        said = [parse_slots(r["said"], ACTIONS, COLOURS, SHAPES) for r in recs]
        colours = Counter(x["colour"] or "" for x in said)
        shapes = Counter(x["object"] or "" for x in said)
        grid.append(
            {
                "colour": colour,
                "shape": shape,
                "recordings": len(recs),
                "colour_said": dict(colours.most_common()),
                "shape_said": dict(shapes.most_common()),
                "colour_right": round(colours[colour] / len(recs), 4),
                "shape_right": round(shapes[shape] / len(recs), 4),
                "exact": round(sum(r["exact"] for r in recs) / len(recs), 4),
            }
        )
    return grid


def generalising(corpus: Corpus, models: ModelRegistry, surveys: SurveyService, name: str | None) -> dict:
    """How one model describes every scene, scored against its own split."""
    lm = models.get(name)
    survey = surveys.survey(lm.name)
    scenes = _scenes(corpus, lm, survey.ids, survey.texts)
    trained = [s for s in scenes.values() if s["split"] == "train"]
    _score(list(scenes.values()), trained)
    novel = [s for s in scenes.values() if s["split"] == "test"]
    split = str(lm.meta.get("split_kind", "scenes"))
    return {
        "model": lm.name,
        "mode": lm.mode,
        "split": split,
        "fold": lm.meta.get("fold"),
        "held_out": held_out(novel) if split == "objects" else [],
        "objects_models": objects_models(models),
        "actions": list(ACTIONS),
        "objects": [f"{c} {s}" for c in COLOURS for s in SHAPES],
        "scenes": list(scenes.values()),
        "train": summary(trained),
        "test": summary(novel),
        "test_object_seen": summary([s for s in novel if s["seen"]["object"]]),
        "test_object_unseen": summary([s for s in novel if not s["seen"]["object"]]),
    }
