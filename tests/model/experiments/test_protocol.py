"""The evaluation engine: seeds, plans, resumability, and equal numbers on the local pool and Ray."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

from model.experiments.protocol import (
    apply_overrides,
    data_digest,
    default_config,
    execute_run,
    plan,
    run_protocol,
    run_seed,
    summarise,
    tasks,
)
from model.experiments.runstore import RunStore
from tests.model.tiny_data import TINY_OVERRIDES, tiny_sequence_set

ROOT = Path(__file__).resolve().parents[3]  # the checkout: `tests.model.tiny_data` and `model` import from it


def tiny_config() -> dict:
    return apply_overrides(default_config(), TINY_OVERRIDES)


def test_every_fold_and_init_gets_its_own_reproducible_seed() -> None:
    seeds = {run_seed(0, k, n) for k in range(10) for n in range(10)}
    assert len(seeds) == 100
    assert run_seed(7, 3, 4) == 7 + 3000 + 4


def test_plan_gives_k_times_n_runs_with_distinct_keys() -> None:
    data = tiny_sequence_set()
    specs = plan("evaluate", "faithful", 3, 2, tiny_config(), data_digest(data))
    assert [(s.fold, s.init) for s in specs] == [(k, n) for k in range(3) for n in range(2)]
    assert len({s.key for s in specs}) == 6
    assert [s.key for s in specs] == [
        s.key for s in plan("evaluate", "faithful", 3, 2, tiny_config(), data_digest(data))
    ]


def test_overrides_set_nested_values_and_reject_unknown_keys() -> None:
    cfg = apply_overrides(default_config(), {"training.psi_s": 1e-3})
    assert cfg["training"]["psi_s"] == 1e-3 and default_config()["training"]["psi_s"] == 5e-4
    with pytest.raises(KeyError, match="training.no_such"):
        apply_overrides(default_config(), {"training.no_such": 1})


def test_data_digest_changes_with_the_data() -> None:
    data = tiny_sequence_set()
    other = tiny_sequence_set()
    other.vision[0] = other.vision[0] + 1e-3
    assert data_digest(data) == data_digest(tiny_sequence_set()) != data_digest(other)


@pytest.mark.slow
def test_a_worker_returns_metrics_per_split_and_the_checkpoint_files() -> None:
    data = tiny_sequence_set()
    (spec,) = plan("evaluate", "faithful", 1, 1, tiny_config(), data_digest(data))
    outcome = execute_run(data, spec)
    assert outcome.ok, outcome.error
    assert set(outcome.metrics) == {"train", "test", "mixed"}
    assert 0.0 <= outcome.metrics["test"]["f1"] <= 1.0
    assert outcome.metrics["train"]["n"] == outcome.metrics["test"]["n"] == 8
    assert "csc.somatosensory.d_rel" in outcome.metrics["train"]
    assert {"meta.json", "model.safetensors"} <= set(outcome.checkpoint)
    again = execute_run(data, spec)
    assert again.metrics == outcome.metrics  # deterministic for a seed


@pytest.mark.slow
def test_a_failing_run_is_reported_not_raised() -> None:
    data = tiny_sequence_set()
    (spec,) = plan("evaluate", "no_such_mode", 1, 1, tiny_config(), data_digest(data))
    outcome = execute_run(data, spec)
    assert not outcome.ok and "no_such_mode" in outcome.error


@pytest.mark.cluster
def test_ray_gives_the_same_numbers_as_the_local_pool(tmp_path) -> None:
    """The CI check of issue 5: 2 folds x 1 init on a local Ray instance == the local engine."""
    ray = pytest.importorskip("ray")
    data = tiny_sequence_set()
    specs = plan("evaluate", "faithful", 2, 1, tiny_config(), data_digest(data))
    local = run_protocol(data, specs, RunStore(tmp_path / "local"), "local", workers=2)
    try:
        remote = run_protocol(data, specs, RunStore(tmp_path / "ray"), "ray", workers=2)
    finally:
        ray.shutdown()
    assert not local.failed and not remote.failed
    assert [r.key for r in local.runs] == [r.key for r in remote.runs]
    for a, b in zip(local.runs, remote.runs, strict=True):
        assert a.metrics == b.metrics  # exactly equal, every split, every measure


DRIVER = textwrap.dedent(
    """
    import sys
    sys.path.insert(0, {here!r})
    from tests.model.tiny_data import tiny_sequence_set
    from model.experiments.protocol import apply_overrides, data_digest, default_config, plan, run_protocol
    from model.experiments.runstore import RunStore

    if __name__ == "__main__":
        data = tiny_sequence_set()
        overrides = {{"training.epochs_auditory": 40, "training.epochs_somatosensory": 20,
                     "training.epochs_visual": 20, "training.epochs_assemblies": 20}}
        config = apply_overrides(default_config(), overrides)
        specs = plan("evaluate", "faithful", 3, 2, config, data_digest(data))
        run_protocol(data, specs, RunStore(sys.argv[1]), "local", workers=2)
    """
)


def _done(db: Path) -> dict[str, tuple[float, int]]:
    if not db.exists():
        return {}
    try:
        with sqlite3.connect(db, timeout=30) as con:
            rows = con.execute("SELECT key, finished, attempts FROM runs WHERE status = 'done'").fetchall()
    except sqlite3.OperationalError:  # the store is being created
        return {}
    return {k: (f, a) for k, f, a in rows}


@pytest.mark.slow
def test_an_evaluation_killed_midway_finishes_on_restart_with_every_run_exactly_once(tmp_path) -> None:
    script = tmp_path / "driver.py"
    script.write_text(DRIVER.format(here=str(ROOT)))
    run_dir = tmp_path / "runs"
    db = run_dir / "runs.sqlite"
    proc = subprocess.Popen([sys.executable, str(script), str(run_dir)], start_new_session=True)
    deadline = time.monotonic() + 240
    while len(_done(db)) < 2:
        assert proc.poll() is None, "the evaluation ended before it could be killed"
        assert time.monotonic() < deadline
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    before = _done(db)
    assert 2 <= len(before) < 6, "kill midway: some runs done, some not"

    subprocess.run([sys.executable, str(script), str(run_dir)], check=True, timeout=300)

    after = _done(db)
    assert len(after) == 6
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 6
        per_run = con.execute(
            "SELECT run_key, COUNT(*) FROM metrics WHERE name = 'f1' GROUP BY run_key"
        ).fetchall()
    assert sorted(n for _, n in per_run) == [3] * 6  # train, test, mixed: once each
    for key, (finished, attempts) in before.items():
        assert after[key] == (finished, attempts) and attempts == 1  # not trained again
    assert sorted(p.name for p in (run_dir / "checkpoints").iterdir()) == sorted(after)

    subprocess.run([sys.executable, str(script), str(run_dir)], check=True, timeout=120)
    assert _done(db) == after  # a third run of the same command finds everything done: trains nothing


def test_summarise_gives_mean_standard_error_and_extremes_per_split() -> None:
    from model.experiments.runstore import RunRecord

    def run(f1: float) -> RunRecord:
        return RunRecord(
            "k", "evaluate", "faithful", 0, 0, 0, {}, {}, "done", 1, 1.0, None, 1.0, {"test": {"f1": f1}}
        )

    s = summarise([run(0.2), run(0.4), run(0.9)])["test"]["f1"]
    assert s["n"] == 3 and s["min"] == 0.2 and s["max"] == 0.9
    assert abs(s["mean"] - 0.5) < 1e-12 and abs(s["sem"] - 0.2081665999) < 1e-9


@pytest.mark.slow
def test_a_run_of_the_objects_split_trains_without_the_held_out_objects(tmp_path) -> None:
    from tests.model.experiments.square_data import square_sequence_set

    data = square_sequence_set()
    specs = plan("evaluate", "faithful", [1], 1, tiny_config(), data_digest(data), split="objects")
    (paper,) = plan("evaluate", "faithful", [1], 1, tiny_config(), data_digest(data))
    assert specs[0].key != paper.key and specs[0].split == "objects"
    result = run_protocol(data, specs, RunStore(tmp_path), "local", workers=1)
    (run,) = result.runs
    assert not result.failed and run.split == "objects"
    assert run.metrics["train"]["n"] == 12 and run.metrics["test"]["n"] == 4
    meta = json.loads((Path(run.checkpoint) / "meta.json").read_text())
    assert meta["split_kind"] == "objects"
    held = {" ".join(rid.split("-")[-3:-1]) for rid in meta["split"]["test"]}
    assert held == {"blue banana", "green dice", "red phone", "yellow apple"}  # fold 1's Latin square


@pytest.mark.cluster
def test_ray_runs_the_objects_split_as_the_local_pool_does(tmp_path) -> None:
    ray = pytest.importorskip("ray")
    from tests.model.experiments.square_data import square_sequence_set

    data = square_sequence_set()
    specs = plan("evaluate", "faithful", [3], 1, tiny_config(), data_digest(data), split="objects")
    local = run_protocol(data, specs, RunStore(tmp_path / "local"), "local", workers=1)
    try:
        remote = run_protocol(data, specs, RunStore(tmp_path / "ray"), "ray", workers=1)
    finally:
        ray.shutdown()
    assert not local.failed and not remote.failed
    assert [(r.split, r.metrics) for r in remote.runs] == [(r.split, r.metrics) for r in local.runs]
    assert remote.runs[0].metrics["test"]["n"] == 4


@dataclass
class _Result:
    metrics: dict
    seconds: float
    artifacts: dict


def batched_echo(data, specs):
    """A batched runner for the test below: every run scores its own seed and the batch's size."""
    return [_Result({"train": {"seed": s.seed, "batch": len(specs)}}, 1.0, {}) for s in specs]


batched_echo.batch_size = 3


def test_a_batched_runner_gets_its_runs_in_batches_and_the_store_one_record_each(tmp_path) -> None:
    specs = [replace(s, seed=10 + i) for i, s in enumerate(plan("echo", "echo", 7, 1, {}, "d"))]
    assert [len(t) for t in tasks(specs, f"{__name__}:batched_echo")] == [3, 3, 1]
    store = RunStore(tmp_path / "runs")
    result = run_protocol(None, specs, store, "local", workers=2, runner=f"{__name__}:batched_echo")
    assert not result.failed and result.executed == 7
    assert [r.metrics["train"]["seed"] for r in result.runs] == [s.seed for s in specs]
    assert sorted(r.metrics["train"]["batch"] for r in result.runs) == [1, 3, 3, 3, 3, 3, 3]
    again = run_protocol(None, specs, store, "local", workers=2, runner=f"{__name__}:batched_echo")
    assert again.executed == 0 and again.skipped == 7


def batched_short(data, specs):
    """A broken batched runner: one result too few."""
    return batched_echo(data, specs)[:-1]


batched_short.batch_size = 2


def test_a_batched_runner_that_breaks_fails_its_runs_and_never_the_driver(tmp_path) -> None:
    specs = [replace(s, seed=10 + i) for i, s in enumerate(plan("echo", "echo", 3, 1, {}, "d"))]
    store = RunStore(tmp_path / "runs")
    result = run_protocol(None, specs, store, "local", workers=1, runner=f"{__name__}:batched_short")
    assert sorted(result.failed) == sorted(s.key for s in specs) and result.executed == 0
    failed = store.runs(keys=[s.key for s in specs], status="failed")  # recorded, retried on restart
    assert len(failed) == 3
