"""`mtrnn report`: write docs/RESULTS.md and docs/figures/*.png from the run store.

mtrnn report                       # store runs/ (or $MTRNN_RUN_DIR), shipped corpus
mtrnn report --run-dir runs --out docs/RESULTS.md --no-pca
"""

from __future__ import annotations

import argparse
from pathlib import Path

from server.settings import REPO_ROOT


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("report", help="write docs/RESULTS.md and its figures from the run store")
    parser.add_argument(
        "--run-dir", type=Path, default=None, help="run store folder (default: $MTRNN_RUN_DIR or runs/)"
    )
    parser.add_argument("--out", type=Path, default=REPO_ROOT / "docs" / "RESULTS.md")
    parser.add_argument(
        "--figures", type=Path, default=None, help="figure folder (default: figures/ beside --out)"
    )
    parser.add_argument("--corpus", type=Path, default=None, help="encoded corpus for the PCA panels")
    parser.add_argument("--no-pca", action="store_true", help="skip the Fig. 10 panels (no corpus needed)")
    parser.add_argument(
        "--command",
        dest="commands",
        action="append",
        default=[],
        help="a command that produced the runs, listed in the report (repeatable)",
    )
    parser.add_argument("--note", dest="notes", action="append", default=[], help="a note for the report")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from model.experiments.report import build_report
    from server.commands.evaluate import load_data, run_store

    store = run_store(args.run_dir)
    data = None
    if not args.no_pca:
        data = load_data(args.corpus)
    figures = args.figures or args.out.parent / "figures"
    report = build_report(store, args.out, figures, data, args.commands, args.notes)
    print(f"wrote {args.out} and {len(report.figures)} figures under {figures}")
    return 0
