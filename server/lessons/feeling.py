"""Lesson 4, feeling: one action on the four shapes of one colour, and why touch alone is ambiguous.

Beside the five joint angles MTRNN_s reads in the paper (4.1.1), each recording's hand path: the
hand's position relative to its start in the torso frame (forward kinematics, `data.nao`), which
does not depend on how the redundant arm was held to follow it (`model.encoding.kinematics`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from data.nao import JOINT_NAMES, forward_kinematics_batch
from data.scenario import ACTIONS, COLOURS, SHAPES
from data.world import FPS
from model.config import MultiMTRNNConfig
from server.lessons import rounded
from server.services.corpus import Corpus
from server.services.errors import Invalid, NotFound
from server.services.models import LoadedModel
from server.services.survey import Survey, SurveyService


def _resample(x: np.ndarray, steps: int = 50) -> np.ndarray:
    """A [T, F] sequence linearly resampled to `steps` steps (compares sequences of any length)."""
    t = np.linspace(0.0, 1.0, len(x))
    grid = np.linspace(0.0, 1.0, steps)
    return np.stack([np.interp(grid, t, x[:, j]) for j in range(x.shape[1])], axis=1)


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(((_resample(a) - _resample(b)) ** 2).mean()))


def _hand_path(entry: Any) -> np.ndarray:
    """The hand's path [T, 3] of a recording relative to its first step, in centimetres, torso frame
    (x forward, y left, z up), by forward kinematics of its joint angles (radians)."""
    hand = forward_kinematics_batch(entry.joints)["hand"]
    return 100.0 * (hand - hand[0])


def _reads(served: LoadedModel) -> tuple[str, str]:
    """What the served model's MTRNN_s reads, its config's `proprioception` ("joints", "joints+hand"
    or "hand"), and which net also reads the object's motion (`object_motion`); a model without a
    MultiMTRNN config (the peer baseline) reads the joint codes and no motion."""
    config = getattr(served.model, "config", None)
    if not isinstance(config, MultiMTRNNConfig):
        return "joints", "none"
    return config.proprioception, config.object_motion


def _find(corpus: Corpus, action: str, colour: str, shape: str) -> Any | None:
    """The corpus entry of a scene (its lowest variant present)."""
    matches = [
        e
        for e in corpus.entries.values()
        if (e.scene.action, e.scene.colour, e.scene.shape) == (action, colour, shape)
    ]
    return min(matches, key=lambda e: e.variant) if matches else None


def _row(survey: Survey, pair: str, what: str, x: Any, y: Any) -> dict:
    """Distances of two recordings: joint angles and hand paths (RMS, resampled) and both Csc spaces."""
    index = {rid: i for i, rid in enumerate(survey.ids)}

    def dist(space: str) -> float:
        c = survey.vectors(space)
        return round(float(np.linalg.norm(c[index[x.id]] - c[index[y.id]])), 4)

    return {
        "pair": pair,
        "what": what,
        "joints_rms": round(_rms(x.proprioception, y.proprioception), 4),
        "hand_rms": round(_rms(_hand_path(x), _hand_path(y)), 4),
        "c_s": dist("s"),
        "c_v": dist("v"),
    }


def _comparison(corpus: Corpus, surveys: SurveyService, action: str) -> dict | None:
    """Why touch alone cannot tell a red apple from a blue phone: compare distances."""
    a = _find(corpus, action, "red", "apple")
    b = _find(corpus, action, "blue", "phone")
    other_action = next(x for x in ACTIONS if x != action)
    c = _find(corpus, other_action, "red", "apple")
    if a is None or b is None or c is None:
        return None
    survey = surveys.survey()
    rows = [
        _row(survey, f"{action} red apple vs {action} blue phone", "same action, different object", a, b),
        _row(
            survey, f"{action} red apple vs {other_action} red apple", "different action, same object", a, c
        ),
    ]
    a2 = next((e for e in corpus.entries.values() if e.scene == a.scene and e.variant != a.variant), None)
    if a2 is not None:
        pair = f"{action} red apple, teacher {a.variant} vs teacher {a2.variant}"
        rows.append(_row(survey, pair, "same scene, another teacher", a, a2))
    return {"ids": [a.id, b.id, c.id], "rows": rows, "model": survey.model}


def feeling(corpus: Corpus, surveys: SurveyService, action: str, colour: str) -> dict:
    """Proprioception of one action on the four shapes of one colour, and the ambiguity of touch."""
    if action not in ACTIONS:
        raise Invalid(f"action must be one of {', '.join(ACTIONS)}")
    if colour not in COLOURS:
        raise Invalid(f"colour must be one of {', '.join(COLOURS)}")
    found = [(shape, _find(corpus, action, colour, shape)) for shape in SHAPES]
    series = [
        {
            "id": e.id,
            "shape": shape,
            "fps": FPS,
            "proprioception": rounded(np.asarray(e.proprioception).T, 4),
            "hand_path": rounded(_hand_path(e).T, 4),
        }
        for shape, e in found
        if e is not None
    ]
    if not series:
        raise NotFound(f"the corpus has no '{action}' on a {colour} object")
    reads, object_motion = _reads(surveys.models.served)
    return {
        "action": action,
        "colour": colour,
        "joint_names": list(JOINT_NAMES),
        "reads": reads,
        "object_motion": object_motion,
        "series": series,
        "comparison": _comparison(corpus, surveys, action),
    }
