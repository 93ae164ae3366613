"""The API's answer for one described recording, shaped once for the route and the CLI.

`POST /api/describe`, `POST /api/scenes/{id}/describe`, `GET /api/uploads/{id}/description` and
`mtrnn describe --json` all answer `description_of(...)`. This module imports no web framework
route nor `server.deps`, so the CLI starts without them.
"""

from __future__ import annotations

from typing import Any

from model.encoding.utterance import PHONEMES
from model.metrics import sentence_exact
from server.schemas.describe import CscVectors, Description, Familiarity, Timings
from server.schemas.timeline import Timeline
from server.services.describe import Result


def rows(array: Any, digits: int = 5) -> list[list[float]]:
    """A 2-D array as rows of rounded floats."""
    return [[round(float(v), digits) for v in row] for row in array]


def description_of(
    result: Result, rid: str, source: str, model: str, timeline: Timeline | None = None
) -> Description:
    """The API's answer for one described recording (also what `mtrnn describe --json` prints)."""
    expected = result.expected
    return Description(
        id=rid,
        source=source,  # type: ignore[arg-type]
        model=model,
        utterance=result.text,
        words=result.words,
        phonemes=result.phonemes,
        expected=expected,
        correct=None if expected is None else sentence_exact(result.text, expected),
        phoneme_labels=list(PHONEMES),
        activity=rows(result.activity, 4),
        target_activity=None if result.target_activity is None else rows(result.target_activity, 4),
        csc=CscVectors(**{k: [round(float(x), 6) for x in v] for k, v in result.csc.items()}),
        timings=Timings(**{k: round(v, 3) for k, v in result.timings.items()}),
        timeline=timeline,
        familiarity=None if result.familiarity is None else Familiarity(**result.familiarity),
        warnings=result.warnings,
    )
