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
    from server.routes.describe import description_of
    from server.settings import Settings
    from server.state import AppState

    state = AppState(Settings.from_env(model=args.model, viser=False))
    try:
        data = args.recording.read_bytes()
    except OSError as exc:
        print(f"error: {exc}")
        return 2
    if len(data) > state.backend.max_upload_bytes:
        print(f"error: {args.recording} is larger than the limit of {state.backend.max_upload_bytes} bytes")
        return 2
    try:
        up = state.describe_upload(data, args.recording.name)
    except state.backend.recording_error as exc:
        print(f"error: {exc}")
        return 2
    answer = description_of(up.result, up.id, "upload", up.model, state.backend.phoneme_labels)
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
