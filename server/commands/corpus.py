"""`mtrnn corpus build` and `mtrnn corpus export`: make the shipped corpora (the paper's, and the wide
variety's with `--variety wide --recordings 16`), write example recordings."""

from __future__ import annotations

import argparse
import logging
import time
from pathlib import Path

from tqdm import tqdm

logger = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("corpus", help="build the simulated corpus or export a recording from it")
    sub = parser.add_subparsers(dest="corpus_command", required=True)

    build = sub.add_parser("build", help="simulate and encode the 64 scenes x 4 (or --recordings) recordings")
    build.add_argument("--seed", type=int, default=0, help="corpus seed (same seed, same bytes)")
    build.add_argument("--workers", type=int, default=2, help="worker processes")
    build.add_argument(
        "--variety",
        choices=("paper", "wide"),
        default="paper",
        help="paper: today's sampling; "
        "wide: table, placement, postures, IK solution, tempo, object form and camera randomised",
    )
    build.add_argument("--recordings", type=int, default=4, help="recordings per scene, 1..16 (default 4)")
    build.add_argument(
        "--out", type=Path, default=None, help="output .npz (default: data/artefacts/corpus.npz)"
    )
    build.set_defaults(func=_build)

    export = sub.add_parser("export", help="write one corpus recording in format v1 (.zip or .npz)")
    export.add_argument("recording", help="recording id (slide-red-apple-2) or scene id (slide-red-apple)")
    export.add_argument("--variant", type=int, default=None, help="variant 0..15 when a scene id is given")
    export.add_argument("--seed", type=int, default=0, help="corpus seed")
    export.add_argument("--variety", choices=("paper", "wide"), default="paper", help="the corpus's variety")
    export.add_argument("--out", type=Path, required=True, help="rec.zip (PNG frames), or rec.npz")
    export.add_argument("--video", action="store_true", help="zip: store the frames as video.mp4")
    export.set_defaults(func=_export)


def _build(args: argparse.Namespace) -> int:
    from data.corpus import build_corpus
    from data.scenario import VARIANTS

    if not 1 <= args.recordings <= len(VARIANTS):
        print(f"error: --recordings must be 1..{len(VARIANTS)}, got {args.recordings}")
        return 2
    start = time.perf_counter()
    with tqdm(total=64 * args.recordings, unit="rec", desc=f"corpus ({args.variety})") as bar:

        def progress(done: int, total: int) -> None:
            bar.total = total
            bar.update(done - bar.n)

        path = build_corpus(
            seed=args.seed,
            workers=args.workers,
            out=args.out,
            progress=progress,
            variety=args.variety,
            recordings_per_scene=args.recordings,
        )
    seconds = time.perf_counter() - start
    print(f"wrote {path} ({path.stat().st_size / 1024**2:.1f} MB) in {seconds:.1f} s wall time")
    return 0


def _export(args: argparse.Namespace) -> int:
    from data.corpus import export_recording
    from data.recording import write_npz, write_zip
    from data.scenario import parse_recording_id

    rid = args.recording
    try:
        parse_recording_id(rid)
        if args.variant is not None:
            print(f"error: {rid!r} is already a recording id; drop --variant")
            return 2
    except ValueError:
        rid = f"{rid}-{args.variant if args.variant is not None else 0}"
        try:
            parse_recording_id(rid)
        except ValueError as exc:
            print(f"error: {args.recording!r} is neither a recording id nor a scene id ({exc})")
            return 2
    suffix = args.out.suffix.lower()
    if suffix not in (".zip", ".npz"):
        print(f"error: --out must end in .zip or .npz, got {args.out}")
        return 2
    recording = export_recording(rid, seed=args.seed, variety=args.variety)
    if suffix == ".npz":
        write_npz(recording, args.out)
    else:
        write_zip(recording, args.out, frames_as="mp4" if args.video else "png")
    print(f"wrote {rid} ({recording.steps} steps, {recording.duration:.2f} s) to {args.out}")
    return 0
