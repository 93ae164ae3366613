"""`mtrnn train`: train one model on one fold of the corpus and save it as a checkpoint.

    mtrnn train --mode end_to_end --out models/quick --epochs-scale 0.1
    mtrnn train --mode end_to_end --split objects --fold 1 --out models/objects-1

`--split` picks the protocol split of the fold (`model.experiments.splits`, as `mtrnn evaluate`):
the paper's 50:50 by scene by default, `objects` / `action-object` (folds 0..3), or `size` with
`--train-scenes`.

`--epochs-scale` multiplies every epoch count the mode reads (`server.jobs.presets.scale_epochs`:
faithful's stages, end_to_end's options, peer's epochs). A progress bar per stage (and per attempt
of a stage that restarts) shows its epochs, loss and time left on stderr."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

from tqdm import tqdm

from server.commands.evaluate import add_assignments, add_split_arguments, checked_split, parse_assignments

logger = logging.getLogger(__name__)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("train", help="train one model on one fold (50:50 by scene) and save it")
    parser.add_argument(
        "--mode", default="faithful", help="training mode: faithful (the paper), end_to_end or peer"
    )
    parser.add_argument(
        "--fold", type=int, default=0, help="which fold of the split (50:50 by scene by default)"
    )
    add_split_arguments(parser, many=False)
    parser.add_argument("--seed", type=int, default=0, help="random initialisation")
    parser.add_argument("--out", type=Path, required=True, help="checkpoint directory to write")
    parser.add_argument(
        "--epochs-scale",
        type=float,
        default=1.0,
        help="multiply every epoch count of the mode (0.1: the Jobs page's quick preset)",
    )
    parser.add_argument("--corpus", type=Path, default=None, help="corpus .npz (default: the shipped one)")
    add_assignments(
        parser,
        "--option",
        "option",
        "a named option of the mode, e.g. assemblies_solver=optimum (faithful) or recombine=0 "
        "(end_to_end); repeatable",
    )
    add_assignments(
        parser,
        "--set",
        "set",
        "override a config value, e.g. training.optimiser=rprop (faithful learns by the paper's rule "
        "by default); repeatable",
    )
    parser.add_argument("--json", action="store_true", help="print the metrics as JSON")
    parser.set_defaults(func=_train)


def _config(args: argparse.Namespace) -> dict:
    """The mode's default config, its --option values, its epochs scaled, then the --set values;
    ValueError if bad."""
    from model.experiments.protocol import apply_overrides, default_config
    from server.jobs.presets import scale_epochs

    try:
        options = parse_assignments(args.option)
        overrides = parse_assignments(args.set)
    except ValueError as err:
        raise ValueError(f"--option and --set take KEY=VALUE, got {err.args[0]!r}") from None
    config = default_config(args.mode)
    if options:
        if "options" not in config:
            raise ValueError(f"mode {args.mode} has no named options")
        config["options"] = options
    try:
        return apply_overrides(scale_epochs(config, args.mode, args.epochs_scale), overrides)
    except KeyError as err:
        raise ValueError(f"--set: {err.args[0]}") from None


class StageBars:
    """One tqdm bar per stage (and per attempt of a restarted stage) on stderr: epochs, loss, ETA."""

    def __init__(self) -> None:
        self.key: tuple | None = None
        self.bar: tqdm | None = None

    def __call__(self, report: dict) -> None:
        key = (report["stage"], report.get("attempt"))
        if key != self.key:
            self.close()
            desc = report["stage"]
            if report.get("attempt"):
                desc += f" (attempt {report['attempt']} of {report['attempts']})"
            self.key, self.bar = key, tqdm(total=report["epochs"], desc=desc, unit="epoch", file=sys.stderr)
        assert self.bar is not None
        self.bar.update(report["epoch"] - self.bar.n)
        self.bar.set_postfix(loss=f"{report['loss']:.4g}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _train(args: argparse.Namespace) -> int:
    from data.corpus import load_corpus
    from model.experiments.evaluation import run_once
    from model.training import MODES

    if args.mode not in MODES:
        print(f"error: unknown mode {args.mode!r}; available: {', '.join(sorted(MODES))}")
        return 2
    checked_split(args.split, args.train_scenes, fold=args.fold)
    try:
        config = _config(args)
        corpus = load_corpus(args.corpus)
    except (FileNotFoundError, ValueError) as err:
        print(f"error: {err}")
        return 2
    bars = StageBars()
    try:
        split = {"split": args.split, "train_scenes": args.train_scenes}
        data = corpus.training_data()
        result = run_once(data, args.mode, args.fold, args.seed, config, args.out, bars, **split)
    except ValueError as err:  # e.g. an unknown --option
        print(f"error: {err}")
        return 2
    finally:
        bars.close()
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
