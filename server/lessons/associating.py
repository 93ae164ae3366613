"""Lesson 6, associating (Fig. 10): the three Csc spaces side by side and what the model says with one
modality muted."""

from __future__ import annotations

import numpy as np
import torch

from data.scenario import ACTIONS, COLOURS, SHAPES
from model.metrics import parse_slots
from server.lessons import rounded
from server.services.corpus import Corpus
from server.services.errors import Invalid
from server.services.models import LoadedModel, ModelRegistry
from server.services.survey import SurveyService

MUTES = ("none", "vision", "proprioception")


def labels(corpus: Corpus, ids: list[str], lm: LoadedModel) -> list[dict]:
    """Slots and split of each recording, for colouring the points."""
    out = []
    for rid in ids:
        e = corpus.entries[rid]
        out.append(
            {
                "id": rid,
                "action": e.scene.action,
                "colour": e.scene.colour,
                "shape": e.scene.shape,
                "split": lm.split_of(rid, e.scene.id),
            }
        )
    return out


def _spaces(surveys: SurveyService, name: str) -> dict:
    spaces = {}
    for space in ("s", "v", "a"):
        pca, coords = surveys.pca2(name, space)
        spaces[space] = {
            "x": rounded(coords[:, 0], 6),
            "y": rounded(coords[:, 1], 6),
            "explained": rounded(pca.explained_variance_ratio_, 4),
        }
    return spaces


def associating(corpus: Corpus, models: ModelRegistry, surveys: SurveyService, rid: str, mute: str) -> dict:
    """The three Csc spaces of the served model side by side, one recording highlighted, and what
    the model says when one modality is muted.

    Muting replaces that modality's abstracted context (c_s,T or c_v,T) by its mean over the corpus:
    the cell assemblies (eq. 17) then receive no information from it about this scene.
    """
    if mute not in MUTES:
        raise Invalid(f"mute must be one of {', '.join(MUTES)}")
    entry = corpus.entry(rid)
    lm = models.served
    survey = surveys.survey(lm.name)
    i = survey.ids.index(rid)
    c_s, c_v = survey.c_s[i].copy(), survey.c_v[i].copy()
    if mute == "vision":
        c_v = survey.c_v.mean(axis=0)
    elif mute == "proprioception":
        c_s = survey.c_s.mean(axis=0)
    with torch.no_grad():
        c_a = lm.model.assemblies(
            torch.as_tensor(c_s, dtype=torch.float32)[None], torch.as_tensor(c_v, dtype=torch.float32)[None]
        )[0].numpy()  # eq. (17)
    said = lm.model.generate_from_csc(c_a, lm.lexicon)
    pca_a, _ = surveys.pca2(lm.name, "a")
    point = pca_a.transform(c_a[None].astype(np.float64))[0]
    near = int(np.argmin(np.linalg.norm(survey.c_a - c_a[None], axis=1)))
    expected = parse_slots(entry.utterance, ACTIONS, COLOURS, SHAPES)
    got = parse_slots(said.text, ACTIONS, COLOURS, SHAPES)
    return {
        "id": rid,
        "model": lm.name,
        "mute": mute,
        "expected": entry.utterance,
        "said": said.text,
        "unmuted": survey.texts[i],
        "slots": {k: {"expected": expected[k], "said": got[k]} for k in expected},
        "index": i,
        "point_a": rounded(point[:2], 6),
        "moved": round(float(np.linalg.norm(c_a - survey.c_a[i])), 6),
        "nearest": {"id": survey.ids[near], "said": survey.texts[near]},
        "labels": labels(corpus, survey.ids, lm),
        "spaces": _spaces(surveys, lm.name),
    }
