"""`mtrnn evaluate`: the paper's protocol (K folds x N initialisations) on the local cores or Ray.

    mtrnn evaluate --mode end_to_end --folds 4 --inits 2
    mtrnn evaluate --mode faithful --folds 2 --inits 1 --engine ray --set training.epochs_auditory=50
    mtrnn evaluate --mode peer --folds 10 --inits 10 --engine ray --address ray://head:10001 --json
    mtrnn evaluate --mode end_to_end --split objects --folds 4 --inits 2      (held-out objects)
    mtrnn evaluate --mode end_to_end --split size --train-scenes 8 16 32 48 --folds 4 --inits 2

`--split` picks the protocol split (`model.experiments.splits`): `scenes`, the paper's 50:50 by
scene (the default); `objects` and `action-object`, Latin squares of held-out pairs with 4 folds;
`size`, the training-size curve: one protocol per `--train-scenes` value, all against the same
novel scenes of each fold.

Results go to the run store in --run-dir (default: `Settings.run_dir`, $MTRNN_RUN_DIR or runs/;
the app's own evaluations keep theirs apart, in its user folder); running the same command again
skips every finished run, so a killed evaluation is resumed by repeating it. `--epochs-scale`
multiplies every epoch count the mode reads (`server.jobs.presets.scale_epochs`), before --set.
A progress bar over the runs shows the time left on stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tqdm import tqdm


def add_engine_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by `evaluate` and `sweep`."""
    parser.add_argument("--folds", type=int, default=10, help="K: 50:50 scene splits (paper: 10)")
    parser.add_argument("--inits", type=int, default=10, help="N: initialisations per fold (paper: 10)")
    parser.add_argument("--engine", choices=("local", "ray"), default="local")
    parser.add_argument("--address", default=None, help="Ray cluster address; none starts a local instance")
    parser.add_argument(
        "--workers", type=int, default=2, help="local processes / CPUs of a local Ray instance"
    )
    parser.add_argument(
        "--run-dir", type=Path, default=None, help="run store folder (default: $MTRNN_RUN_DIR or runs/)"
    )
    parser.add_argument("--seed", type=int, default=0, help="base seed; run (k, n) uses seed + 1000 k + n")
    parser.add_argument("--corpus", type=Path, default=None, help="encoded corpus (default: the shipped one)")
    example = "training.epochs_auditory=200"
    add_assignments(parser, "--set", "overrides", f"override a config value, e.g. {example} (repeatable)")
    parser.add_argument("--json", action="store_true", help="print the summary and every run as JSON")


def add_assignments(parser: argparse.ArgumentParser, flag: str, dest: str, text: str) -> None:
    """A repeatable KEY=VALUE option (read by `parse_assignments`)."""
    parser.add_argument(flag, dest=dest, action="append", default=[], metavar="KEY=VALUE", help=text)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("evaluate", help="K folds x N inits of one training mode (resumable)")
    parser.add_argument("--mode", required=True, help="faithful, end_to_end or peer")
    add_split_arguments(parser, many=True)
    parser.add_argument(
        "--epochs-scale",
        type=float,
        default=1.0,
        help="multiply every epoch count of the mode (0.1: the Jobs page's quick preset)",
    )
    add_engine_arguments(parser)
    parser.set_defaults(func=run)


def add_split_arguments(parser: argparse.ArgumentParser, many: bool) -> None:
    """--split and --train-scenes (`many`: a list of sizes, one protocol each), for evaluate and train."""
    from model.experiments.splits import SPLITS, TRAINING_SIZES

    parser.add_argument(
        "--split",
        choices=SPLITS,
        default="scenes",
        help="protocol split: scenes (the paper's 50:50, default), objects or action-object (held-out "
        "pairs, 4 folds), size (the training-size curve, with --train-scenes)",
    )
    sizes = " ".join(map(str, TRAINING_SIZES))
    parser.add_argument(
        "--train-scenes",
        type=int,
        nargs="+" if many else None,
        default=None,
        help=f"size split: the scenes to train on ({'the curve: ' + sizes if many else 'e.g. 16'})",
    )


def checked_split(split: str, train_scenes: int | None, folds: int = 1, fold: int = 0) -> None:
    """`server.jobs.bounds.check_split` for a command: its message ends the command."""
    from server.jobs.bounds import check_split
    from server.services.errors import Invalid

    try:
        check_split(split, train_scenes, folds=folds, fold=fold)
    except Invalid as err:
        raise SystemExit(f"error: {err}") from None


def parse_assignments(items: list[str]) -> dict[str, Any]:
    """["training.psi_s=5e-4", ...] -> {"training.psi_s": 0.0005}; values are JSON where they parse.
    ValueError(item) for an item that is not KEY=VALUE."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key:
            raise ValueError(item)
        try:
            out[key] = json.loads(raw)
        except json.JSONDecodeError:
            out[key] = raw
    return out


def parse_overrides(items: list[str]) -> dict[str, Any]:
    """The --set values (`parse_assignments`); a malformed one ends the command with its error."""
    try:
        return parse_assignments(items)
    except ValueError as err:
        raise SystemExit(f"error: --set needs KEY=VALUE, got {err.args[0]!r}") from None


def engine_options(args: argparse.Namespace, progress: Any) -> dict[str, Any]:
    """`run_protocol`'s engine, workers, address and progress from the command's arguments."""
    return {"engine": args.engine, "workers": args.workers, "address": args.address, "progress": progress}


def run_store(run_dir: Path | None) -> Any:
    """The run store in `run_dir`, by default the app's (`Settings.run_dir`: $MTRNN_RUN_DIR or runs/)."""
    from model.experiments.runstore import RunStore
    from server.settings import Settings

    return RunStore(run_dir or Settings.from_env().run_dir)


def load_data(corpus_path: Path | None) -> Any:
    """The whole encoded corpus as a SequenceSet (folds split it by scene inside each run)."""
    from data.corpus import load_corpus

    return load_corpus(corpus_path).training_data()


def build_config(
    overrides: dict[str, Any], mode: str = "faithful", epochs_scale: float = 1.0
) -> dict[str, Any]:
    """The mode's defaults, every epoch count times `epochs_scale`, then `overrides`."""
    from model.experiments.protocol import apply_overrides, default_config
    from server.jobs.presets import scale_epochs

    try:
        return apply_overrides(scale_epochs(default_config(mode), mode, epochs_scale), overrides)
    except (KeyError, ValueError) as err:
        raise SystemExit(f"error: {err.args[0]}") from None


def with_progress(store: Any, specs: list, run: Callable[[Any], Any]) -> Any:
    """`run(progress)` under a bar over the runs of `specs` (those already done in `store` counted)."""
    bar, update = progress_bar(len(specs), len(store.done_keys([s.key for s in specs])))
    try:
        return run(update)
    finally:
        bar.close()


def progress_bar(total: int, already: int) -> tuple[tqdm, Any]:
    """A bar over the runs (those of an earlier try counted), with the time left."""
    bar = tqdm(total=total, initial=already, desc="runs", unit="run", file=sys.stderr)

    def update(event: dict) -> None:
        bar.update(1)
        test = event["metrics"].get("test", {})
        if "f1" in test:
            bar.set_postfix(test_f1=f"{test['f1']:.3f}", s=f"{event['seconds']:.0f}")

    return bar, update


def run(args: argparse.Namespace) -> int:
    sizes = args.train_scenes or [None]
    for size in sizes:
        checked_split(args.split, size, folds=args.folds)
    config = build_config(parse_overrides(args.overrides), args.mode, args.epochs_scale)
    data = load_data(args.corpus)
    store = run_store(args.run_dir)
    answers = [evaluate_split(args, config, data, store, size) for size in sizes]
    if args.json:
        print(json.dumps(answers[0] if len(answers) == 1 else answers, indent=1, sort_keys=True))
    else:
        for answer in answers:
            print_summary(answer)
    return 1 if any(a["failed"] for a in answers) else 0


def evaluate_split(args: argparse.Namespace, config: dict, data: Any, store: Any, size: int | None) -> dict:
    """One protocol (K folds x N inits) on the command's split (and `size` training scenes)."""
    from model.experiments.protocol import data_digest, plan, run_protocol, summarise

    where = {"split": args.split, "train_scenes": size}
    specs = plan("evaluate", args.mode, args.folds, args.inits, config, data_digest(data), args.seed, **where)
    result = with_progress(
        store, specs, lambda update: run_protocol(data, specs, store, **engine_options(args, update))
    )
    return {
        "mode": args.mode,
        **where,
        "folds": args.folds,
        "inits": args.inits,
        "engine": args.engine,
        "run_dir": str(store.run_dir),
        "executed": result.executed,
        "skipped": result.skipped,
        "failed": len(result.failed),
        "seconds": result.seconds,
        "summary": summarise(result.runs),
        "runs": [
            {
                "key": r.key,
                "fold": r.fold,
                "init": r.init,
                "seed": r.seed,
                "seconds": r.seconds,
                "metrics": r.metrics,
            }
            for r in result.runs
        ],
    }


def print_summary(answer: dict) -> None:
    sized = f", {answer['train_scenes']} training scenes" if answer["train_scenes"] else ""
    counts = (
        f"{answer['executed']} trained now, {answer['skipped']} from the store, {answer['failed']} failed"
    )
    print(
        f"{answer['mode']} on the {answer['split']} split{sized}: {len(answer['runs'])} runs ({counts}) "
        f"in {answer['seconds']:.0f} s; store {answer['run_dir']}"
    )
    names = ("sentence_exact", "f1", "edit_distance", "word_accuracy")
    print(f"{'split':<6} " + " ".join(f"{n:>22}" for n in names))
    for split in ("train", "test", "mixed"):
        values = answer["summary"].get(split, {})
        cells = []
        for n in names:
            v = values.get(n)
            cells.append(f"{v['mean']:.3f} +- {v['sem']:.3f} (max {v['max']:.3f})" if v else "-")
        print(f"{split:<6} " + " ".join(f"{c:>22}" for c in cells))
