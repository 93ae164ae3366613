"""Parameter sweeps of the paper: psi_s over the whole model (4.3, Fig. 9) and psi over the cosine
experiment (3.2.2, Fig. 3), both as runs of the evaluation engine (`model.experiments.protocol`).

The psi_s sweep plans K folds x N inits per value with `training.psi_s` set, all in one store
experiment ("psi_s") so that every value shares the same folds and seeds; its table gives, per
value, the mixed F1 and edit distance (Fig. 9 a, b), d_avg / d_rel (c) and d_inter / d_intra (d)
of the somatosensory Csc, each as mean and standard error over runs.

The cosine sweep runs `model.experiments.cosine.run_cosine` once per (psi, run) as an engine task, so it
spreads over cores and Ray workers the same way; its table gives epochs, d_avg and d_rel (Fig. 3).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from model.experiments.protocol import Engine, ProgressFn, ProtocolResult, apply_overrides, plan, run_protocol
from model.experiments.runstore import RunRecord, RunSpec, RunStore

PSI_S_PAPER = (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2)  # {1, 2, 5} x 10^-k, k in {4, 3, 2}
PSI_COSINE_PAPER = (0.0, 1e-5, 5e-5, 2e-4)  # Fig. 3 (c-f)
COSINE_RUNNER = "model.experiments.sweeps:cosine_run"
CSC_SPACE_SWEPT = "somatosensory"  # Fig. 9 (c, d) measure the somatosensory Csc


def psi_s_specs(
    values: Sequence[float],
    mode: str,
    folds: int,
    inits: int,
    config: Mapping[str, Any],
    digest: str,
    base_seed: int = 0,
) -> list[RunSpec]:
    """Every (psi_s, fold, init) run; the same folds and seeds for every value (paired design)."""
    specs: list[RunSpec] = []
    for value in values:
        cfg = apply_overrides(config, {"training.psi_s": float(value)})
        specs += plan("psi_s", mode, folds, inits, cfg, digest, base_seed, params={"psi_s": float(value)})
    return specs


def run_psi_s_sweep(
    data: Any,
    values: Sequence[float],
    mode: str,
    folds: int,
    inits: int,
    store: RunStore,
    config: Mapping[str, Any],
    digest: str,
    engine: Engine = "local",
    workers: int = 2,
    address: str | None = None,
    base_seed: int = 0,
    progress: ProgressFn | None = None,
) -> ProtocolResult:
    specs = psi_s_specs(values, mode, folds, inits, config, digest, base_seed)
    return run_protocol(data, specs, store, engine, workers, address, progress=progress)


# --- the cosine experiment as engine tasks ---------------------------------------------------------


@dataclass
class CosineRunResult:
    """One cosine run in the shape the engine expects of a runner's result."""

    metrics: dict[str, dict[str, float]]
    seconds: float
    artifacts: dict[str, Any] = field(default_factory=dict)


def cosine_run(
    data: Any,
    mode: str,
    fold: int,
    seed: int,
    config: Any = None,
    out_dir: Path | None = None,
) -> CosineRunResult:
    """Engine runner for one run of the cosine experiment (3.2.2); the psi travels in `mode`
    ("cosine:<psi>"), so the engine's (data, mode, fold, seed) signature carries everything."""
    from model.experiments.cosine import train_cosine_once

    psi = float(mode.split(":", 1)[1])
    started = time.perf_counter()
    run = train_cosine_once(psi, seed)
    return CosineRunResult(
        metrics={
            "cosine": {
                "epochs": float(run.epochs),
                "converged": float(run.converged),
                "d_avg": run.d_avg,
                "d_rel": run.d_rel,
                "target_d_avg": run.target_d_avg,
                "target_d_rel": run.target_d_rel,
            }
        },
        seconds=time.perf_counter() - started,
        artifacts={"csc": run.snapshots[-1]["csc"] if run.snapshots else []},
    )


def cosine_specs(values: Sequence[float], runs: int, base_seed: int = 0) -> list[RunSpec]:
    """`runs` seeded runs per psi, the same seeds for every psi (paired, as `model.experiments.cosine`);
    mode "cosine:<psi>" carries the value to the runner."""
    return [
        RunSpec(
            experiment="cosine",
            mode=f"cosine:{float(v)!r}",
            fold=i,
            init=r,
            seed=base_seed + r,
            params={"psi": float(v)},
        )
        for i, v in enumerate(values)
        for r in range(runs)
    ]


def run_cosine_sweep(
    values: Sequence[float],
    runs: int,
    store: RunStore,
    engine: Engine = "local",
    workers: int = 2,
    address: str | None = None,
    base_seed: int = 0,
    progress: ProgressFn | None = None,
) -> ProtocolResult:
    specs = cosine_specs(values, runs, base_seed)
    return run_protocol(None, specs, store, engine, workers, address, runner=COSINE_RUNNER, progress=progress)


# --- tables -----------------------------------------------------------------------------------------


def mean_sem(values: Sequence[float]) -> tuple[float, float, int]:
    a = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=np.float64)
    if a.size == 0:
        return math.nan, math.nan, 0
    sem = float(a.std(ddof=1) / math.sqrt(a.size)) if a.size > 1 else 0.0
    return float(a.mean()), sem, int(a.size)


def _metric(run: RunRecord, split: str, name: str) -> float | None:
    return run.metrics.get(split, {}).get(name)


def psi_s_table(runs: Sequence[RunRecord], space: str = CSC_SPACE_SWEPT) -> list[dict[str, Any]]:
    """Per psi_s: mean and standard error over runs of the Fig. 9 (a-d) measures."""
    by_value: dict[float, list[RunRecord]] = {}
    for r in runs:
        by_value.setdefault(float(r.params["psi_s"]), []).append(r)
    rows = []
    for value in sorted(by_value):
        group = by_value[value]
        row: dict[str, Any] = {"psi_s": value, "runs": len(group)}
        for label, split, name in (
            ("mixed_f1", "mixed", "f1"),
            ("mixed_edit_distance", "mixed", "edit_distance"),
            ("test_f1", "test", "f1"),
            ("test_sentence_exact", "test", "sentence_exact"),
            ("d_avg", "train", f"csc.{space}.d_avg"),
            ("d_rel", "train", f"csc.{space}.d_rel"),
            ("d_inter", "train", f"csc.{space}.d_inter"),
            ("d_intra", "train", f"csc.{space}.d_intra"),
        ):
            mean, sem, _ = mean_sem([_metric(r, split, name) for r in group])  # type: ignore[misc]
            row[label], row[f"{label}_sem"] = mean, sem
        rows.append(row)
    return rows


def cosine_table(runs: Sequence[RunRecord]) -> list[dict[str, Any]]:
    """Per psi: mean and standard error over runs of epochs, d_avg and d_rel (Fig. 3 a, b)."""
    by_value: dict[float, list[RunRecord]] = {}
    for r in runs:
        by_value.setdefault(float(r.params["psi"]), []).append(r)
    rows = []
    for value in sorted(by_value):
        group = by_value[value]
        row: dict[str, Any] = {"psi": value, "runs": len(group)}
        for name in ("epochs", "converged", "d_avg", "d_rel", "target_d_avg", "target_d_rel"):
            mean, sem, n = mean_sem([_metric(r, "cosine", name) for r in group])  # type: ignore[misc]
            if n:
                row[name], row[f"{name}_sem"] = mean, sem
        rows.append(row)
    return rows
