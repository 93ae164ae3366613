"""`mtrnn describe RECORDING [--json]`: what the served model says about a recording file.

The same code path as ``POST /api/describe``, so the answer is the same. It loads only what
describing needs, the model and its lexicon; the corpus is read only for a model whose meta.json
has no lexicon (its words) or whose checkpoint has no familiarity (the recordings it learned
from, `server.services.models`); without a corpus such a model answers without familiarity.
The answer goes to stdout; errors and logs to stderr.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from server.services.describe import DescribeService
    from server.settings import Settings


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("describe", help="describe a recording (.zip or .npz, format v1)")
    parser.add_argument("recording", type=Path, help="a recording in format v1")
    parser.add_argument("--json", action="store_true", help="print the API's JSON answer")
    parser.add_argument("--model", default=None, help="model folder name under data/artefacts/models")
    parser.set_defaults(func=run)


def _error(message: str) -> int:
    print(f"error: {message}", file=sys.stderr)
    return 2


def describer(settings: Settings) -> DescribeService:
    """The describe service over the settings' models, with no corpus scenes to serve."""
    from data.corpus import Corpus as Recordings
    from server.services.corpus import Corpus
    from server.services.describe import DescribeService
    from server.services.errors import Unavailable
    from server.services.models import ModelRegistry

    def recordings() -> dict:
        try:
            return Corpus.load(settings).entries
        except FileNotFoundError:
            return {}

    no_scenes = Corpus(Recordings(entries=[], seed=0))
    try:
        models = ModelRegistry(settings.models_dir, [], settings.model, None, recordings=recordings)
    except Unavailable:  # a model without a lexicon of its own speaks the corpus's words
        models = ModelRegistry.serving(settings, Corpus.load(settings))
    return DescribeService(no_scenes, models)


def run(args: argparse.Namespace) -> int:
    from data.recording import MAX_UPLOAD_BYTES, RecordingError
    from server.services.answers import description_of
    from server.settings import Settings

    settings = Settings.from_env(model=args.model, viser=False)
    try:
        data = args.recording.read_bytes()
    except OSError as exc:
        return _error(str(exc))
    if len(data) > MAX_UPLOAD_BYTES:
        return _error(f"{args.recording} is larger than the limit of {MAX_UPLOAD_BYTES} bytes")
    try:
        up = describer(settings).describe_upload(data, args.recording.name)
    except (RecordingError, FileNotFoundError) as exc:  # a bad recording, or no model to serve
        return _error(str(exc))
    answer = description_of(up.result, up.id, "upload", up.model)
    if args.json:
        print(answer.model_dump_json(indent=1))
    else:
        print(answer.utterance)
        if answer.expected is not None:
            verdict = "correct" if answer.correct else "differs"
            print(f"expected: {answer.expected} ({verdict})")
        print(f"phonemes: {' '.join(answer.phonemes)}")
        if answer.familiarity is not None:
            prop, vis = answer.familiarity.proprioception, answer.familiarity.vision
            print(f"familiarity: proprioception {100 * prop:.0f} %, vision {100 * vis:.0f} %")
        for warning in answer.warnings:
            print(f"warning: {warning}")
        print(f"model: {answer.model}; {answer.timings.total_ms:.0f} ms")
    return 0
