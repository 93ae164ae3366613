"""Lesson 7, generalising: how one model describes every scene, training vs novel scenes, and for
novel scenes whether their object and action pairings were ever seen in training."""

from __future__ import annotations

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


def generalising(corpus: Corpus, models: ModelRegistry, surveys: SurveyService, name: str | None) -> dict:
    """How one model describes every scene, scored against its own split."""
    lm = models.get(name)
    survey = surveys.survey(lm.name)
    scenes = _scenes(corpus, lm, survey.ids, survey.texts)
    trained = [s for s in scenes.values() if s["split"] == "train"]
    _score(list(scenes.values()), trained)
    novel = [s for s in scenes.values() if s["split"] == "test"]
    return {
        "model": lm.name,
        "mode": lm.mode,
        "actions": list(ACTIONS),
        "objects": [f"{c} {s}" for c in COLOURS for s in SHAPES],
        "scenes": list(scenes.values()),
        "train": summary(trained),
        "test": summary(novel),
        "test_object_seen": summary([s for s in novel if s["seen"]["object"]]),
        "test_object_unseen": summary([s for s in novel if not s["seen"]["object"]]),
    }
