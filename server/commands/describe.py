"""`mtrnn describe RECORDING [--json]`: what the served model says about a recording file.

The same code path as ``POST /api/describe``, so the answer is the same.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("describe", help="describe a recording (.zip or .npz, format v1)")
    parser.add_argument("recording", type=Path, help="a recording in format v1")
    parser.add_argument("--json", action="store_true", help="print the API's JSON answer")
    parser.add_argument("--model", default=None, help="model folder name under data/artefacts/models")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from data.recording import MAX_UPLOAD_BYTES, RecordingError
    from server.routes.describe import description_of
    from server.services.corpus import Corpus
    from server.services.describe import DescribeService
    from server.services.models import ModelRegistry
    from server.settings import Settings

    settings = Settings.from_env(model=args.model, viser=False)
    corpus = Corpus.load(settings)
    models = ModelRegistry.serving(settings, corpus)
    try:
        data = args.recording.read_bytes()
    except OSError as exc:
        print(f"error: {exc}")
        return 2
    if len(data) > MAX_UPLOAD_BYTES:
        print(f"error: {args.recording} is larger than the limit of {MAX_UPLOAD_BYTES} bytes")
        return 2
    try:
        up = DescribeService(corpus, models).describe_upload(data, args.recording.name)
    except RecordingError as exc:
        print(f"error: {exc}")
        return 2
    answer = description_of(up.result, up.id, "upload", up.model)
    if args.json:
        print(answer.model_dump_json(indent=1))
    else:
        print(answer.utterance)
        if answer.expected is not None:
            verdict = "correct" if answer.correct else "differs"
            print(f"expected: {answer.expected} ({verdict})")
        print(f"phonemes: {' '.join(answer.phonemes)}")
        print(f"model: {answer.model}; {answer.timings.total_ms:.0f} ms")
    return 0
