"""The report's numbers as Markdown: the paper's (4.3), the modes' tables beside them, and what the
runs of a table were trained with (their epoch budgets, folds and inits)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from model.experiments.runstore import RunRecord

# Paper, 4.3: means over 100 runs and the best network (psi_s = 5e-4).
PAPER = {
    "train": {"f1": 0.952, "edit_distance": 0.0185},
    "test": {"f1": 0.281, "edit_distance": 0.417},
    "mixed": {"f1": 0.617, "edit_distance": 0.219},
    "best_train": {"f1": 0.984, "edit_distance": 0.00364},
    "best_test": {"f1": 0.638, "edit_distance": 0.154},
}
MODES = ("faithful", "end_to_end", "peer")
SPLITS = ("train", "test", "mixed")
COLUMNS = (
    ("sentence_exact", "exact"),
    ("f1", "phoneme F1"),
    ("edit_distance", "edit distance"),
    ("word_accuracy", "word acc."),
    ("slot_action", "action"),
    ("slot_colour", "colour"),
    ("slot_object", "object"),
)


def fmt(mean: float | None, sem: float | None = None, digits: int = 3) -> str:
    if mean is None or (isinstance(mean, float) and math.isnan(mean)):
        return "–"
    return f"{mean:.{digits}f}" + (f" ± {sem:.{digits}f}" if sem is not None and sem > 0 else "")


def budget(runs: Sequence[RunRecord]) -> dict[str, Any]:
    """The epoch budget the runs used (from their stored configs)."""
    if not runs:
        return {}
    cfg = runs[0].config
    if "training" in cfg:
        budget = {k: v for k, v in cfg["training"].items() if k.startswith("epochs")}
        if runs[0].mode == "end_to_end":  # its own stages (model.training.end_to_end.EndToEndOptions)
            from dataclasses import asdict

            from model.training.end_to_end import EndToEndOptions

            options = cfg.get("end_to_end") or _meta(runs[0]).get("end_to_end") or asdict(EndToEndOptions())
            budget = {f"end_to_end.{k}": v for k, v in options.items() if k.endswith("epochs")}
        return budget
    return {k: v for k, v in cfg.items() if k.startswith("epochs")}


def _meta(run: RunRecord) -> dict[str, Any]:
    """meta.json of a run's checkpoint ({} without one)."""
    path = Path(run.checkpoint or "") / "meta.json"
    return json.loads(path.read_text()) if run.checkpoint and path.is_file() else {}


def paper_budget() -> dict[str, Any]:
    from model.config import TrainingConfig

    return {k: v for k, v in vars(TrainingConfig()).items() if k.startswith("epochs")}


def one_config(runs: list[RunRecord]) -> list[RunRecord]:
    """The runs of the mode's most evaluated config (latest on a tie): budgets are never mixed."""
    groups: dict[str, list[RunRecord]] = {}
    for r in runs:
        groups.setdefault(json.dumps(r.config, sort_keys=True), []).append(r)
    if len(groups) <= 1:
        return runs
    return max(groups.values(), key=lambda g: (len(g), max(r.finished or 0.0 for r in g)))


def folds_inits(runs: Sequence[RunRecord]) -> str:
    return f"{len({r.fold for r in runs})} folds × {len({r.init for r in runs})} inits = {len(runs)} runs"


def mode_table(summaries: dict[str, dict], counts: dict[str, str]) -> list[str]:
    lines = [
        "| mode | split | " + " | ".join(label for _, label in COLUMNS) + " |",
        "| --- | --- | " + " | ".join("---" for _ in COLUMNS) + " |",
    ]
    for mode in MODES:
        if mode not in summaries:
            continue
        for split in SPLITS:
            s = summaries[mode].get(split, {})
            cells = [fmt(s.get(k, {}).get("mean"), s.get(k, {}).get("sem")) for k, _ in COLUMNS]
            lines.append(f"| {mode} ({counts[mode]}) | {split} | " + " | ".join(cells) + " |")
    return lines


def paper_table(summaries: dict[str, dict]) -> list[str]:
    modes = [m for m in MODES if m in summaries]
    lines = [
        "| measure | paper | " + " | ".join(modes) + " |",
        "| --- | --- | " + " | ".join("---" for _ in modes) + " |",
    ]
    rows = [
        ("train F1 (mean)", "train", "f1", "mean", PAPER["train"]["f1"]),
        ("test F1 (mean)", "test", "f1", "mean", PAPER["test"]["f1"]),
        ("mixed F1 (mean)", "mixed", "f1", "mean", PAPER["mixed"]["f1"]),
        ("train edit distance (mean)", "train", "edit_distance", "mean", PAPER["train"]["edit_distance"]),
        ("test edit distance (mean)", "test", "edit_distance", "mean", PAPER["test"]["edit_distance"]),
        ("mixed edit distance (mean)", "mixed", "edit_distance", "mean", PAPER["mixed"]["edit_distance"]),
        ("train F1 (best run)", "train", "f1", "max", PAPER["best_train"]["f1"]),
        ("test F1 (best run)", "test", "f1", "max", PAPER["best_test"]["f1"]),
        (
            "train edit distance (best run)",
            "train",
            "edit_distance",
            "min",
            PAPER["best_train"]["edit_distance"],
        ),
        (
            "test edit distance (best run)",
            "test",
            "edit_distance",
            "min",
            PAPER["best_test"]["edit_distance"],
        ),
    ]
    for label, split, metric, stat, paper in rows:
        cells = [fmt(summaries[m].get(split, {}).get(metric, {}).get(stat), digits=4) for m in modes]
        lines.append(f"| {label} | {paper:g} | " + " | ".join(cells) + " |")
    return lines


def best_runs(runs: Sequence[RunRecord]) -> dict[str, dict[str, float]]:
    """The paper's "best network": the run with the highest test F1, with its train numbers."""
    best = max(runs, key=lambda r: r.metrics.get("test", {}).get("f1", -1.0))
    return {s: best.metrics.get(s, {}) for s in SPLITS}
