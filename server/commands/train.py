"""`mtrnn train`: train one MultiMTRNN on one fold of the corpus and save it as a checkpoint."""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from tqdm import tqdm

from server.commands.evaluate import add_assignments, parse_assignments

logger = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("train", help="train one model on one fold (50:50 by scene) and save it")
    parser.add_argument(
        "--mode", default="faithful", help="training mode: faithful (the paper) or end_to_end"
    )
    parser.add_argument("--fold", type=int, default=0, help="which 50:50 split by scene")
    parser.add_argument("--seed", type=int, default=0, help="random initialisation")
    parser.add_argument("--out", type=Path, required=True, help="checkpoint directory to write")
    parser.add_argument("--epochs-scale", type=float, default=1.0, help="multiply every stage's epochs")
    parser.add_argument("--corpus", type=Path, default=None, help="corpus .npz (default: the shipped one)")
    add_assignments(
        parser,
        "--option",
        "option",
        "a named option of the mode, e.g. assemblies_solver=optimum (faithful) or recombine=0 "
        "(end_to_end); repeatable",
    )
    parser.add_argument("--json", action="store_true", help="print the metrics as JSON")
    parser.set_defaults(func=_train)


def _train(args: argparse.Namespace) -> int:
    from data.corpus import load_corpus
    from model.config import MultiMTRNNConfig
    from model.experiments.evaluation import run_once
    from model.training import MODES

    if args.mode not in MODES:
        print(f"error: unknown mode {args.mode!r}; available: {', '.join(sorted(MODES))}")
        return 2
    try:
        corpus = load_corpus(args.corpus)
    except FileNotFoundError as err:
        print(f"error: {err}")
        return 2
    config = MultiMTRNNConfig()
    config.training = config.training.scaled(args.epochs_scale)
    try:
        config.options = parse_assignments(args.option)
    except ValueError as err:
        print(f"error: --option takes KEY=VALUE, got {err.args[0]!r}")
        return 2
    data = corpus.training_data()

    bars: dict[str, tqdm] = {}

    def progress(report: dict) -> None:
        stage = report["stage"]
        if stage not in bars:
            for bar in bars.values():
                bar.close()
            bars[stage] = tqdm(total=report["epochs"], desc=stage, unit="epoch")
        bar = bars[stage]
        bar.update(report["epoch"] - bar.n)
        bar.set_postfix(loss=f"{report['loss']:.4g}")

    try:
        result = run_once(data, args.mode, args.fold, args.seed, config, out_dir=args.out, progress=progress)
    except ValueError as err:  # e.g. an unknown --option
        print(f"error: {err}")
        return 2
    for bar in bars.values():
        bar.close()
    if args.json:
        print(json.dumps(result.metrics, indent=2))
    else:
        for split in ("train", "test", "mixed"):
            m = result.metrics[split]
            print(
                f"{split:5s}  exact {m['sentence_exact']:.3f}  F1 {m['f1']:.3f}"
                f"  edit {m['edit_distance']:.3f}  words {m['word_accuracy']:.3f}"
                f"  slots {m['slot_action']:.2f}/{m['slot_colour']:.2f}/{m['slot_object']:.2f}"
            )
        print(f"saved {args.out} ({result.seconds:.1f} s)")
    return 0
