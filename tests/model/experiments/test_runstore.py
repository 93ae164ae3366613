"""The run store: planned runs, atomic completion, resumability."""

from __future__ import annotations

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
