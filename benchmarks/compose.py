"""Composition benchmark (issue 16): does `end_to_end` describe colour x shape pairs it never saw?

Runs named option sets of `EndToEndOptions` over folds x inits of a split (`objects`: four colour x
shape pairs held out in a Latin square, `model.experiments.splits`; `scenes`: the paper's 50:50 by
scene, to check that nothing regresses) and prints, per set and split, the held-out recordings'
sentence exact, phoneme F1 and the action, colour and object (shape) slot accuracies, mean and
standard deviation over the runs, then every run. Run (fold k, init n) trains with seed 1000 k + n,
as the protocol does. Results: docs/experiments/compose.md.

    .venv/bin/python benchmarks/compose.py [--sets before,recolour] [--splits objects,scenes]
        [--folds 0,1] [--inits 0] [--workers 2] [--json out.json]

One run costs ~50-60 s on an idle core (one torch thread per worker process).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

SETS: dict[str, dict] = {  # every set names both options: the defaults changed with issue 16
    "before": {"recombine_objects": 0.0, "factorised_vision": False},  # the recipe before issue 16
    "recolour": {"recombine_objects": 1.0, "factorised_vision": False},  # today's default
    "factorised": {"recombine_objects": 0.0, "factorised_vision": True},
    "recolour+factorised": {"recombine_objects": 1.0, "factorised_vision": True},
}
COLUMNS = ("sentence_exact", "f1", "slot_action", "slot_colour", "slot_object")
HEADERS = ("exact", "F1", "action", "colour", "object")

_DATA = None


def _worker_init() -> None:
    import torch

    torch.set_num_threads(1)


def run_one(options: dict, split: str, fold: int, init: int) -> dict:
    """Train `end_to_end` with `options` on one fold of `split`; the held-out recordings' scores."""
    global _DATA
    from data.corpus import load_corpus
    from model.config import MultiMTRNNConfig
    from model.experiments.evaluation import score
    from model.experiments.splits import split_indices
    from model.training import train

    if _DATA is None:
        _DATA = load_corpus().training_data()
    train_idx, test_idx = split_indices(_DATA.ids, _DATA.utterances, fold, split)
    config = MultiMTRNNConfig()
    config.options = dict(options)
    start = time.perf_counter()
    trained = train(_DATA.subset(train_idx), mode="end_to_end", config=config, seed=1000 * fold + init)
    seconds = time.perf_counter() - start
    metrics = score(trained.model, _DATA.subset(test_idx), trained.lexicon)
    stages = {f"seconds_{k}": v for k, v in trained.meta["seconds"].items()}
    return {k: metrics[k] for k in COLUMNS} | {"seconds": seconds} | stages


def _table(results: list[dict]) -> str:
    lines = [
        "| set | split | runs | " + " | ".join(HEADERS) + " | s/run |",
        "| --- | --- | --- | " + " | ".join("---" for _ in HEADERS) + " | --- |",
    ]
    groups: dict[tuple[str, str], list[dict]] = {}
    for r in results:
        groups.setdefault((r["set"], r["split"]), []).append(r)
    for (name, split), runs in groups.items():
        cells = []
        for k in COLUMNS:
            v = np.array([r[k] for r in runs])
            cells.append(f"{v.mean():.3f} ± {v.std():.3f}")
        seconds = np.mean([r["seconds"] for r in runs])
        lines.append(f"| {name} | {split} | {len(runs)} | " + " | ".join(cells) + f" | {seconds:.0f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", default=",".join(SETS), help=f"comma-separated, of {sorted(SETS)}")
    parser.add_argument("--splits", default="objects,scenes")
    parser.add_argument("--folds", default="0,1")
    parser.add_argument("--inits", default="0")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--json", type=Path, help="write every run's scores here")
    args = parser.parse_args(argv)
    names = args.sets.split(",")
    unknown = [n for n in names if n not in SETS]
    if unknown:
        parser.error(f"unknown sets {unknown}; known: {sorted(SETS)}")
    jobs = [
        (name, split, int(fold), int(init))
        for name in names
        for split in args.splits.split(",")
        for fold in args.folds.split(",")
        for init in args.inits.split(",")
    ]
    results: list[dict] = []
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers, initializer=_worker_init) as pool:
        futures = {pool.submit(run_one, SETS[n], s, f, i): (n, s, f, i) for n, s, f, i in jobs}
        for future in as_completed(futures):
            name, split, fold, init = futures[future]
            row = {"set": name, "split": split, "fold": fold, "init": init, **future.result()}
            results.append(row)
            scores = " ".join(f"{h} {row[k]:.3f}" for h, k in zip(HEADERS, COLUMNS, strict=True))
            print(f"{name} {split} fold {fold} init {init}: {scores} ({row['seconds']:.0f} s)", flush=True)
    order = {(n, s, f, i): k for k, (n, s, f, i) in enumerate(jobs)}
    results.sort(key=lambda r: order[(r["set"], r["split"], r["fold"], r["init"])])
    print(f"\n{len(results)} runs in {time.perf_counter() - start:.0f} s wall\n")
    print(_table(results))
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
