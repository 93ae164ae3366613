"""Parameter sweeps of the paper: psi_s over the whole model (4.3, Fig. 9) and psi over the cosine
experiment (3.2.2, Fig. 3), both as runs of the evaluation engine (`model.experiments.protocol`).

The psi_s sweep plans K folds x N inits per value with `training.psi_s` set, all in one store
experiment ("psi_s") so that every value shares the same folds and seeds; its table gives, per
value, the mixed F1 and edit distance (Fig. 9 a, b), d_avg / d_rel (c) and d_inter / d_intra (d)
of the somatosensory Csc, each as mean and standard error over runs. Its faithful runs go through
the batched runner `psi_s_runs`: the values of one (fold, init) share MTRNN_a, which psi_s never
reaches (`model.training.faithful.train_faithful_variants`).

The cosine sweep stores one run per (psi, seed) and trains them in vectorised batches of
`cosine_runs.batch_size` runs, each batch an engine task, so it spreads over cores and Ray workers
the same way; its table gives epochs, d_avg and d_rel (Fig. 3).
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from model.experiments.protocol import apply_overrides, plan
from model.experiments.runstore import RunRecord, RunSpec
from model.metrics import mean_sem, paired_difference

PSI_S_PAPER = (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2)  # {1, 2, 5} x 10^-k, k in {4, 3, 2}
PSI_COSINE_PAPER = (0.0, 1e-5, 5e-5, 2e-4)  # Fig. 3 (c-f)
COSINE_RUNNER = "model.experiments.sweeps:cosine_runs"
PSI_S_RUNNER = "model.experiments.sweeps:psi_s_runs"  # faithful sweeps; other modes use run_once
CSC_SPACE_SWEPT = "somatosensory"  # Fig. 9 (c, d) measure the somatosensory Csc


def psi_s_specs(
    values: Sequence[float],
    mode: str,
    folds: int,
    inits: int,
    config: Mapping[str, Any],
    digest: str,
    base_seed: int = 0,
    split: str = "scenes",
    train_scenes: int | None = None,
) -> list[RunSpec]:
    """Every (psi_s, fold, init) run; the same folds and seeds for every value (paired design), on
    one protocol split (`model.experiments.splits`; the paper's by default). Ordered by fold and
    init, so that the values of one (fold, init) follow each other (`psi_s_runs` batches them)."""
    specs: list[RunSpec] = []
    for value in values:
        cfg = apply_overrides(config, {"training.psi_s": float(value)})
        where = {"params": {"psi_s": float(value)}, "split": split, "train_scenes": train_scenes}
        specs += plan("psi_s", mode, folds, inits, cfg, digest, base_seed, **where)
    return sorted(specs, key=lambda spec: (spec.fold, spec.init))


@dataclass
class SweepRunResult:
    """One psi_s run in the shape the engine expects of a runner's result."""

    metrics: dict[str, Any]
    seconds: float
    checkpoint: dict[str, bytes]
    artifacts: dict[str, Any] = field(default_factory=dict)


def psi_s_runs(data: Any, specs: Sequence[RunSpec]) -> list[SweepRunResult]:
    """Batched engine runner for a faithful psi_s sweep: the specs of one (fold, seed, split) train
    together with `train_faithful_variants` (one MTRNN_a, then each value's encoders and assemblies),
    and each is scored and saved as `run_once` would; a run's seconds are its own stages plus an
    equal share of the shared one."""
    from model.experiments.evaluation import scored_run, split_sets
    from model.training.faithful import train_faithful_variants

    groups: dict[tuple, list[int]] = {}
    for i, spec in enumerate(specs):
        if spec.mode != "faithful":
            raise ValueError(f"psi_s_runs trains faithful runs, not {spec.mode!r}")
        groups.setdefault((spec.fold, spec.seed, spec.split, spec.train_scenes), []).append(i)
    results: list[SweepRunResult | None] = [None] * len(specs)
    for (fold, seed, split, train_scenes), members in groups.items():
        train_set, test_set = split_sets(data, fold, split, train_scenes)
        trained = train_faithful_variants(train_set, [specs[i].config for i in members], seed)
        shared = trained[0].meta["seconds"]["auditory"]
        for i, model in zip(members, trained, strict=True):
            own = sum(model.meta["seconds"].values()) - shared + shared / len(members)
            start = time.perf_counter() - own  # scored_run adds the scoring
            with tempfile.TemporaryDirectory(prefix="mtrnn-run-") as tmp:
                run = scored_run(
                    model, data, fold, seed, train_set, test_set, start, tmp, split, train_scenes
                )
                files = {p.name: p.read_bytes() for p in sorted(Path(tmp).iterdir()) if p.is_file()}
            results[i] = SweepRunResult(run.metrics, run.seconds, files)
    return [r for r in results if r is not None]


psi_s_runs.batch_size = len(PSI_S_PAPER) + 1  # one (fold, init) of the paper's values and psi_s = 0


# --- the cosine experiment as engine tasks ---------------------------------------------------------


@dataclass
class CosineRunResult:
    """One cosine run in the shape the engine expects of a runner's result."""

    metrics: dict[str, dict[str, float]]
    seconds: float
    artifacts: dict[str, Any] = field(default_factory=dict)


def cosine_runs(data: Any, specs: Sequence[RunSpec]) -> list[CosineRunResult]:
    """Batched engine runner for the cosine experiment (3.2.2): the runs of `specs` learn together
    (`train_cosine_runs`), each with its `config["psi"]` and the optional "optimiser", "zeta_gain"
    and "max_epochs" of its `CosineSetup`; runs that need another setup (or, under a rule without
    per-run steps, another psi) form their own pass. The experiment needs no data."""
    from model.experiments.cosine import CosineSetup, train_cosine_runs

    passes: dict[tuple, list[int]] = {}
    for i, spec in enumerate(specs):
        setup = CosineSetup(**{k: spec.config[k] for k in ("optimiser", "max_epochs") if k in spec.config})
        psi = None if setup.optimiser == "paper" else spec.config["psi"]
        passes.setdefault((setup.optimiser, setup.max_epochs, psi), []).append(i)
    results: list[CosineRunResult | None] = [None] * len(specs)
    for (optimiser, max_epochs, _), members in passes.items():
        setup = CosineSetup(optimiser=optimiser, max_epochs=max_epochs)
        started = time.perf_counter()
        runs = train_cosine_runs(
            [float(specs[i].config["psi"]) for i in members],
            [specs[i].seed for i in members],
            setup,
            [float(specs[i].config.get("zeta_gain", setup.zeta_gain)) for i in members]
            if optimiser == "paper"
            else None,
        )
        share = (time.perf_counter() - started) / len(members)
        for i, run in zip(members, runs, strict=True):
            results[i] = CosineRunResult(
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
                seconds=share,
                artifacts={"csc": run.snapshots[-1]["csc"]},
            )
    return [r for r in results if r is not None]


cosine_runs.batch_size = 25  # runs per vectorised pass: 400 runs are 16 engine tasks


def cosine_specs(
    values: Sequence[float], runs: int, base_seed: int = 0, rule: Mapping[str, Any] | None = None
) -> list[RunSpec]:
    """`runs` seeded runs per psi, the same seeds for every psi (paired, as `model.experiments.cosine`);
    the config {"psi": value, **rule} carries the value and the learning rule ({"optimiser",
    "zeta_gain"}, default the cosine setup's) to the runner."""
    from model.experiments.cosine import CosineSetup

    rule = dict(rule or {"optimiser": CosineSetup.optimiser, "zeta_gain": CosineSetup.zeta_gain})
    return [
        RunSpec(
            experiment="cosine",
            mode="cosine",
            fold=i,
            init=r,
            seed=base_seed + r,
            config={"psi": float(v), **rule},
            params={"psi": float(v), **rule},
        )
        for i, v in enumerate(values)
        for r in range(runs)
    ]


# --- tables -----------------------------------------------------------------------------------------


def _metric(run: RunRecord, split: str, name: str) -> float | None:
    return run.metrics.get(split, {}).get(name)


def _by_value(runs: Sequence[RunRecord], param: str) -> list[tuple[float, list[RunRecord]]]:
    """The runs grouped by the value of sweep parameter `param`, in increasing order."""
    groups: dict[float, list[RunRecord]] = {}
    for r in runs:
        groups.setdefault(float(r.params[param]), []).append(r)
    return sorted(groups.items())


def _versus_zero(
    row: dict[str, Any], pairs: Sequence[tuple[RunRecord, RunRecord]], split: str, measures: Mapping[str, str]
) -> None:
    """Into `row`, for each (label, metric) of `measures`: the mean and standard error of the paired
    difference (run - its run without forcing), the paired t-test's p and the pairs it counted, as
    "<label>_vs_0", "<label>_vs_0_sem", "<label>_vs_0_p", "<label>_vs_0_n"."""
    for label, name in measures.items():
        diff, sem, n, p = paired_difference(
            [_metric(r, split, name) for r, _ in pairs], [_metric(b, split, name) for _, b in pairs]
        )
        row[f"{label}_vs_0"], row[f"{label}_vs_0_sem"], row[f"{label}_vs_0_p"] = diff, sem, p
        row[f"{label}_vs_0_n"] = n


def psi_s_table(runs: Sequence[RunRecord], space: str = CSC_SPACE_SWEPT) -> list[dict[str, Any]]:
    """Per psi_s: mean and standard error over runs of the Fig. 9 (a-d) measures, their seconds, and
    for psi_s > 0 the paired difference of the novel scenes' sentence exact and phoneme F1 to psi_s = 0
    on the same (fold, init) (mean, standard error, p of the paired t-test, as the paper's 4.3:
    "test_sentence_exact_vs_0", "..._sem", "..._p")."""
    groups = _by_value(runs, "psi_s")
    baseline = {(r.fold, r.init): r for r in dict(groups).get(0.0, [])}
    rows = []
    for value, group in groups:
        row: dict[str, Any] = {
            "psi_s": value,
            "runs": len(group),
            "seconds": sum(r.seconds or 0.0 for r in group),
        }
        pairs = [(r, baseline[(r.fold, r.init)]) for r in group if (r.fold, r.init) in baseline]
        if value != 0.0 and pairs:
            _versus_zero(row, pairs, "test", {"test_sentence_exact": "sentence_exact", "test_f1": "f1"})
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
            mean, sem, _ = mean_sem([_metric(r, split, name) for r in group])
            row[label], row[f"{label}_sem"] = mean, sem
        rows.append(row)
    return rows


def cosine_rule(run: RunRecord) -> tuple[str, float]:
    """(optimiser, zeta_gain) a cosine run learned with; runs stored before the paper's rule was
    selectable learned with sign-based RPROP."""
    return str(run.params.get("optimiser", "rprop")), float(run.params.get("zeta_gain", 1.0))


def cosine_table(runs: Sequence[RunRecord], rule: tuple[str, float] | None = None) -> list[dict[str, Any]]:
    """Per psi: mean and standard error over runs of epochs, d_avg and d_rel (Fig. 3 a, b), of the
    runs learned with `rule` (optimiser, zeta_gain; default the cosine setup's), their seconds, and
    for psi > 0 the paired difference of d_avg and d_rel to psi = 0 on the same seeds (mean,
    standard error, p of the paired t-test: "d_rel_vs_0", "d_rel_vs_0_sem", "d_rel_vs_0_p")."""
    from model.experiments.cosine import CosineSetup

    rule = rule or (CosineSetup.optimiser, CosineSetup.zeta_gain)
    runs = [r for r in runs if cosine_rule(r) == rule]
    groups = _by_value(runs, "psi")
    baseline = {r.seed: r for r in dict(groups).get(0.0, [])}
    rows = []
    for value, group in groups:
        row: dict[str, Any] = {
            "psi": value,
            "runs": len(group),
            "seconds": sum(r.seconds or 0.0 for r in group),
        }
        for name in ("epochs", "converged", "d_avg", "d_rel", "target_d_avg", "target_d_rel"):
            mean, sem, n = mean_sem([_metric(r, "cosine", name) for r in group])
            if n:
                row[name], row[f"{name}_sem"] = mean, sem
        pairs = [(r, baseline[r.seed]) for r in group if r.seed in baseline]
        if value != 0.0 and pairs:  # the same seeds without forcing: differences and a paired t-test
            _versus_zero(row, pairs, "cosine", {"d_avg": "d_avg", "d_rel": "d_rel"})
        rows.append(row)
    return rows
