"""The report's sections on the protocol's harder splits (`model.experiments.splits`): per
Latin-square split a table of the modes on its novel side (exact, F1, and the action, colour and
shape words apart), and the training-size curve as a table and a figure (exact on the same novel
scenes against the number of scenes trained on). Each appears only when the store holds its runs."""

from __future__ import annotations

import json
from typing import Any

from model.experiments.protocol import summarise
from model.experiments.report import figures
from model.experiments.report.tables import MODES, budget, fmt, folds_inits, one_config
from model.experiments.runstore import RunRecord, RunStore

SQUARES = {
    "objects": (
        "Objects never seen (`--split objects`)",
        "a fold holds out four colour x shape objects in a Latin square (every colour and every shape is "
        "still seen in training with three other partners) and tests all their recordings; 4 folds cover "
        "the 16 objects.",
    ),
    "action-object": (
        "Actions with shapes never seen together (`--split action-object`)",
        "a fold holds out four action x shape pairs in a Latin square, in every colour; 4 folds cover "
        "the 16 pairs.",
    ),
}
COLUMNS = (
    ("sentence_exact", "exact"),
    ("f1", "phoneme F1"),
    ("slot_action", "action"),
    ("slot_colour", "colour"),
    ("slot_object", "shape"),
)


def _by_mode(store: RunStore, split: str) -> dict[str, list[RunRecord]]:
    """Each mode's evaluation runs on `split` (of its most evaluated config), modes without runs left out."""
    runs = {m: one_config(store.runs(experiment="evaluate", mode=m, split=split)) for m in MODES}
    return {m: r for m, r in runs.items() if r}


def _header(first: list[str], labels: list[str]) -> list[str]:
    return [
        "| " + " | ".join(first + labels) + " |",
        "| " + " | ".join("---" for _ in first + labels) + " |",
    ]


def squares(page: Any, store: RunStore) -> None:
    """A table per Latin-square split with runs: the modes on its held-out side."""
    for split, (title, what) in SQUARES.items():
        runs = _by_mode(store, split)
        if not runs:
            continue
        tests = {m: summarise(r).get("test", {}) for m, r in runs.items()}
        page.report.data.setdefault("splits", {})[split] = {
            m: {"summary": tests[m], "runs": len(runs[m]), "budget": budget(runs[m])} for m in runs
        }
        page.md += [
            f"## {title}",
            "",
            f"Mean ± standard error over runs, on the test side (the held-out recordings): {what} "
            "Colour and shape are the slot accuracies of the colour and the shape word.",
            "",
            *_header(["mode"], [label for _, label in COLUMNS]),
        ]
        for m, summary in tests.items():
            cells = [fmt(summary.get(k, {}).get("mean"), summary.get(k, {}).get("sem")) for k, _ in COLUMNS]
            page.md.append(f"| {m} ({folds_inits(runs[m])}) | " + " | ".join(cells) + " |")
        page.md += ["", "Epoch budgets used:", ""]
        page.md += [f"- {m}: `{json.dumps(budget(r), sort_keys=True)}`" for m, r in runs.items()] + [""]


def size_curve(page: Any, store: RunStore) -> None:
    """The training-size curve: test exact per mode and number of training scenes, table and figure."""
    runs = _by_mode(store, "size")
    if not runs:
        return
    curve: dict[str, list[dict[str, Any]]] = {}
    for m, mode_runs in runs.items():
        for size in sorted({r.train_scenes for r in mode_runs if r.train_scenes}):
            group = [r for r in mode_runs if r.train_scenes == size]
            exact = summarise(group).get("test", {}).get("sentence_exact", {})
            point = {
                "train_scenes": size,
                "mean": exact.get("mean"),
                "sem": exact.get("sem"),
                "runs": len(group),
            }
            curve.setdefault(m, []).append(point)
    page.report.data["size_curve"] = curve
    sizes = sorted({p["train_scenes"] for points in curve.values() for p in points})
    path = page.figure("size_curve.png")
    figures.figure_size_curve(curve, path)
    page.md += [
        "## Training-size curve (`--split size`)",
        "",
        "Sentence exact on the same novel scenes (per fold the last quarter of its seeded scene order, "
        "16 scenes) when training on the first N of the other 48 (nested: a smaller set is part of a "
        "larger one). Mean ± standard error over runs; the runs per point in brackets.",
        "",
        *_header(["mode"], [f"{n} scenes" for n in sizes]),
    ]
    for m, points in curve.items():
        at = {p["train_scenes"]: p for p in points}
        cells = [fmt(at[n]["mean"], at[n]["sem"]) + f" ({at[n]['runs']})" if n in at else "–" for n in sizes]
        page.md.append(f"| {m} | " + " | ".join(cells) + " |")
    page.md += ["", page.image("training-size curve", path), ""]
