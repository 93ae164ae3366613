"""The run store: planned runs, atomic completion, resumability."""

from __future__ import annotations

import dataclasses
import sqlite3

import pytest

from model.experiments.runstore import RunSpec, RunStore


def _spec(fold: int = 0, init: int = 0, psi: float | None = None) -> RunSpec:
    params = {} if psi is None else {"psi_s": psi}
    return RunSpec(
        "evaluate", "faithful", fold, init, 1000 * fold + init, {"training": {"x": 1}}, params, "d1"
    )


def test_run_key_is_stable_and_depends_on_everything_that_changes_the_numbers() -> None:
    a = _spec()
    assert a.key == _spec().key
    assert len({a.key, _spec(fold=1).key, _spec(init=1).key, _spec(psi=1e-4).key}) == 4
    other_data = RunSpec("evaluate", "faithful", 0, 0, 0, {"training": {"x": 1}}, {}, "d2")
    other_config = RunSpec("evaluate", "faithful", 0, 0, 0, {"training": {"x": 2}}, {}, "d1")
    assert len({a.key, other_data.key, other_config.key}) == 3


def test_finish_commits_metrics_per_split_and_done_keys_skip_them(tmp_path) -> None:
    store = RunStore(tmp_path)
    specs = [_spec(0), _spec(1)]
    store.register(specs)
    assert store.done_keys() == set()
    store.mark_running(specs[0].key)
    path = store.write_checkpoint(specs[0].key, {"meta.json": b"{}", "model.safetensors": b"xx"})
    store.finish(
        specs[0].key,
        {"train": {"f1": 0.9, "n": 8}, "test": {"f1": 0.5}, "mixed": {"f1": 0.7}},
        1.5,
        str(path),
        {"csc": [[0.0, 1.0]]},
    )
    assert store.done_keys() == {specs[0].key}
    (run,) = store.runs()
    assert run.metrics == {"train": {"f1": 0.9, "n": 8.0}, "test": {"f1": 0.5}, "mixed": {"f1": 0.7}}
    assert run.attempts == 1 and run.seconds == 1.5 and run.config == {"training": {"x": 1}}
    assert (path / "model.safetensors").read_bytes() == b"xx"
    assert store.artifact(specs[0].key, "csc") == [[0.0, 1.0]]
    # registering again (a restarted command) leaves the finished run as it was
    store.register(specs)
    assert store.runs()[0].finished == run.finished
    assert len(store.runs(status=None)) == 2


def test_a_failed_transaction_leaves_no_partial_metrics(tmp_path) -> None:
    store = RunStore(tmp_path)
    spec = _spec()
    store.register([spec])
    with pytest.raises(KeyError):
        store.finish("not-a-run", {"train": {"f1": 1.0}}, 1.0)
    assert sqlite3.connect(store.path).execute("SELECT COUNT(*) FROM metrics").fetchone()[0] == 0
    assert store.done_keys() == set()


def test_checkpoint_write_replaces_an_older_attempt(tmp_path) -> None:
    store = RunStore(tmp_path)
    store.write_checkpoint("k", {"a": b"1", "old": b"x"})
    path = store.write_checkpoint("k", {"a": b"2"})
    assert sorted(p.name for p in path.iterdir()) == ["a"] and (path / "a").read_bytes() == b"2"
    assert [p.name for p in store.checkpoint_dir.iterdir()] == ["k"]


def test_runs_of_other_splits_get_their_own_keys_and_the_papers_keep_theirs() -> None:
    a = _spec()
    assert a.key == "a478fc15606de4d407a3"  # stored before there were other splits: never changes
    assert dataclasses.replace(a, split="scenes").key == a.key
    keys = {
        a.key,
        dataclasses.replace(a, split="objects").key,
        dataclasses.replace(a, split="action-object").key,
        dataclasses.replace(a, split="size", train_scenes=8).key,
        dataclasses.replace(a, split="size", train_scenes=16).key,
    }
    assert len(keys) == 5


def test_the_store_keeps_each_runs_split_and_filters_by_it(tmp_path) -> None:
    store = RunStore(tmp_path)
    specs = [_spec(), dataclasses.replace(_spec(), split="size", train_scenes=8)]
    store.register(specs)
    for spec in specs:
        store.finish(spec.key, {"test": {"f1": 0.5}}, 1.0)
    assert [(r.split, r.train_scenes) for r in store.runs()] == [("scenes", None), ("size", 8)]
    assert [r.key for r in store.runs(split="size")] == [specs[1].key]


def test_an_older_store_gains_the_split_columns_with_its_runs_on_the_papers_split(tmp_path) -> None:
    old = tmp_path / "runs.sqlite"
    with sqlite3.connect(old) as db:  # the runs table as the first stores wrote it
        db.executescript(
            "CREATE TABLE configs (hash TEXT PRIMARY KEY, json TEXT NOT NULL);"
            "CREATE TABLE runs (key TEXT PRIMARY KEY, experiment TEXT NOT NULL, mode TEXT NOT NULL,"
            " fold INTEGER NOT NULL, init INTEGER NOT NULL, seed INTEGER NOT NULL, config_hash TEXT NOT NULL,"
            " params TEXT NOT NULL, data_digest TEXT NOT NULL, status TEXT NOT NULL,"
            " attempts INTEGER NOT NULL DEFAULT 0, seconds REAL, checkpoint TEXT, host TEXT,"
            " created REAL NOT NULL, finished REAL,"
            " error TEXT);"
            "INSERT INTO configs VALUES ('h', '{}');"
            "INSERT INTO runs(key, experiment, mode, fold, init, seed, config_hash, params, data_digest,"
            " status, created) VALUES ('k', 'evaluate', 'faithful', 0, 0, 0, 'h', '{}', 'd', 'done', 0);"
        )
    store = RunStore(tmp_path)
    assert [(r.key, r.split, r.train_scenes) for r in store.runs()] == [("k", "scenes", None)]
    assert RunStore(tmp_path).runs(split="scenes")[0].key == "k"  # opened again: nothing to add
