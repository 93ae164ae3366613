"""Lesson 5, abstracting (3.2.2, Fig. 3): snapshots of the live cosine run and the stored sweeps.

The live run itself is a job kind (`server.jobs.kinds`, "cosine") of the app's one job system.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from model.experiments.runstore import DB_NAME, RunStore
from model.experiments.sweeps import cosine_table, psi_s_table
from model.metrics import d_avg, d_rel
from server.lessons import rounded


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


def stored_sweeps(run_dir: Path) -> dict:
    """The psi_s sweep (Fig. 9) and the cosine sweep (Fig. 3 a-b) from the protocol's run store,
    as `model.experiments.sweeps` tabulates them, if they have been run. Never creates a store."""
    if not (run_dir / DB_NAME).is_file():
        return {"available": False, "reason": f"no run store at {run_dir} yet", "psi_s": [], "cosine": []}
    store = RunStore(run_dir)
    psi_s = _clean(psi_s_table(store.runs(experiment="psi_s")))
    cosine = _clean(cosine_table(store.runs(experiment="cosine")))
    reason = "" if psi_s else f"the run store at {run_dir} holds no psi_s sweep yet"
    return {"available": bool(psi_s), "reason": reason, "psi_s": psi_s, "cosine": cosine}
