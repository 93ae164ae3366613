"""Lesson 5, abstracting (3.2.2, Fig. 3): snapshots of the live cosine run and the stored sweeps.

The live run itself is a job kind (`server.jobs.kinds`, "cosine") of the app's one job system.
The sweeps come from the protocol's run store (`settings.run_dir`, made by `mtrnn sweep`, not
shipped) or, where it holds none, from the report that ships them (`settings.figures_dir`'s
results.json, which the Results page reads): a fresh clone shows the same numbers.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from model.experiments.runstore import DB_NAME, RunStore
from model.experiments.sweeps import cosine_table, psi_s_table
from model.metrics import d_avg, d_rel
from server.lessons import rounded

REPORT = "results.json"  # what `mtrnn report` writes into the figures folder


def snapshot(info: dict) -> dict:
    """One Csc snapshot of the cosine run: the network's abstracted c_T of the four sequences
    (eq. 3 at t = T) and the self-organising targets (eq. 12), with d_avg and d_rel (eqs. 14-15)."""
    points = np.asarray(info["csc"], dtype=np.float64)
    targets = np.asarray(info["targets"], dtype=np.float64)
    return {
        "epoch": int(info["epoch"]),
        "error": round(float(info.get("error", info.get("loss", 0.0))), 7),
        "points": rounded(points, 4),
        "targets": rounded(targets, 4),
        "d_avg": round(d_avg(points), 5),
        "d_rel": round(d_rel(points), 5),
        "target_d_avg": round(d_avg(targets), 5),
        "target_d_rel": round(d_rel(targets), 5),
    }


def _clean(rows: list[dict]) -> list[dict]:
    """Sweep table rows with NaN (no value) as None, so they are valid JSON."""
    return [
        {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}
        for row in rows
    ]


def _from_store(run_dir: Path) -> tuple[list[dict], list[dict]]:
    """The psi_s and cosine tables of the run store at `run_dir` ([] without one; never creates it)."""
    if not (run_dir / DB_NAME).is_file():
        return [], []
    store = RunStore(run_dir)
    return psi_s_table(store.runs(experiment="psi_s")), cosine_table(store.runs(experiment="cosine"))


def _from_report(figures_dir: Path) -> tuple[list[dict], list[dict]]:
    """The psi_s and cosine tables the report tabulated (the same `model.experiments.sweeps` rows)
    from <figures_dir>/results.json ([] for a table it lacks or a file that is not the report's)."""
    try:
        data = json.loads((figures_dir / REPORT).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return [], []

    def table(key: str, column: str) -> list[dict]:
        rows = data.get(key) if isinstance(data, dict) else None
        if not isinstance(rows, list) or not all(isinstance(r, dict) and column in r for r in rows):
            return []
        return rows

    return table("psi_s", "psi_s"), table("cosine", "psi")


def stored_sweeps(run_dir: Path, figures_dir: Path) -> dict:
    """The psi_s sweep (Fig. 9) and the cosine sweep (Fig. 3 a-b) as `model.experiments.sweeps`
    tabulates them: each from the run store at `run_dir` if it holds it, else from the shipped
    report in `figures_dir`. Never creates a store."""
    store_psi_s, store_cosine = _from_store(run_dir)
    report_psi_s, report_cosine = _from_report(figures_dir)
    psi_s = _clean(store_psi_s or report_psi_s)
    cosine = _clean(store_cosine or report_cosine)
    if psi_s:
        reason = ""
    elif (run_dir / DB_NAME).is_file():
        reason = f"neither the run store at {run_dir} nor {figures_dir / REPORT} holds a psi_s sweep yet"
    else:
        reason = f"no run store at {run_dir} yet and no psi_s sweep in {figures_dir / REPORT}"
    return {"available": bool(psi_s), "reason": reason, "psi_s": psi_s, "cosine": cosine}
