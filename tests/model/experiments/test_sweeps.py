"""Sweeps: paired designs over psi, and the Fig. 9 / Fig. 3 tables with means and standard errors."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from model.config import ZETA_GAIN
from model.experiments.cosine import CosineSetup, train_cosine_runs
from model.experiments.protocol import default_config, execute_task, tasks
from model.experiments.runstore import RunRecord
from model.experiments.sweeps import (
    COSINE_RUNNER,
    PSI_S_RUNNER,
    cosine_runs,
    cosine_specs,
    cosine_table,
    psi_s_runs,
    psi_s_specs,
    psi_s_table,
)
from model.metrics import mean_sem
from tests.model.tiny_corpus import tiny_config, tiny_corpus


def test_the_psi_s_sweep_uses_the_same_folds_and_seeds_for_every_value() -> None:
    specs = psi_s_specs([1e-4, 5e-4], "faithful", folds=2, inits=2, config=default_config(), digest="d")
    assert len(specs) == 8
    by_value = {}
    for s in specs:
        assert s.config["training"]["psi_s"] == s.params["psi_s"]
        by_value.setdefault(s.params["psi_s"], []).append((s.fold, s.init, s.seed))
    assert by_value[1e-4] == by_value[5e-4]
    assert len({s.key for s in specs}) == 8
    # the values of one (fold, init) follow each other: one batch of psi_s_runs trains them together
    assert [(s.fold, s.init) for s in specs[:2]] == [(0, 0), (0, 0)]
    assert [c[0].params["psi_s"] for c in tasks(specs, PSI_S_RUNNER)] == [1e-4]


def test_psi_s_runs_score_each_value_as_run_once_would(tmp_path) -> None:
    from model.experiments.evaluation import run_once

    data = tiny_corpus(variants=2)
    config = tiny_config(epochs=2).to_dict()
    specs = psi_s_specs([0.0, 5e-2], "faithful", folds=1, inits=1, config=config, digest="d")
    results = psi_s_runs(data, specs)
    assert len(results) == 2 and all(r.seconds > 0 for r in results)
    for spec, result in zip(specs, results, strict=True):
        alone = run_once(data, "faithful", spec.fold, spec.seed, config=spec.config)
        assert result.metrics["train"]["f1"] == pytest.approx(alone.metrics["train"]["f1"])
        somatosensory = result.metrics["train"]["csc"]["somatosensory"]
        assert somatosensory == pytest.approx(alone.metrics["train"]["csc"]["somatosensory"])
        assert {"model.safetensors", "meta.json"} <= set(result.checkpoint)
    outcomes = execute_task(data, specs, PSI_S_RUNNER)  # the engine keeps the checkpoints
    assert [o.ok for o in outcomes] == [True, True] and all(o.checkpoint for o in outcomes)
    with pytest.raises(ValueError, match="faithful"):
        psi_s_runs(data, [replace(specs[0], mode="peer")])


@pytest.mark.slow
def test_cosine_runs_share_seeds_across_psi_and_learn_in_batches() -> None:
    specs = cosine_specs([0.0, 5e-5], runs=3)
    assert [s.seed for s in specs[:3]] == [s.seed for s in specs[3:]] == [0, 1, 2]
    assert COSINE_RUNNER == "model.experiments.sweeps:cosine_runs"
    assert specs[3].config == {"psi": 5e-5, "optimiser": "paper", "zeta_gain": ZETA_GAIN}
    short = [replace(s, config=s.config | {"max_epochs": 50}) for s in specs]
    short[0] = replace(short[0], config=short[0].config | {"optimiser": "rprop"})  # a pass of its own
    results = cosine_runs(None, short)
    assert len(results) == 6
    for result in results:
        m = result.metrics["cosine"]
        assert 0 < m["epochs"] <= 50 and 0 < m["d_rel"] <= 1 and m["d_avg"] > 0 and result.seconds > 0
        assert len(result.artifacts["csc"]) == 4  # four phase-shifted sequences (3.2.2)
    # each result is its own spec's run: the same as that run learning alone
    alone = train_cosine_runs(5e-5, [1], CosineSetup(max_epochs=50))[0]
    assert results[4].metrics["cosine"]["d_rel"] == pytest.approx(alone.d_rel, abs=1e-5)
    assert results[4].metrics["cosine"]["epochs"] == alone.epochs


def _run(psi: float, fold: int, f1_train: float, f1_test: float, d_inter: float) -> RunRecord:
    train = {
        "f1": f1_train,
        "edit_distance": 1 - f1_train,
        "csc.somatosensory.d_avg": 1.0,
        "csc.somatosensory.d_rel": 0.9,
        "csc.somatosensory.d_inter": d_inter,
        "csc.somatosensory.d_intra": 0.5,
    }
    test = {"f1": f1_test, "edit_distance": 1 - f1_test, "sentence_exact": 0.0}
    mixed = {"f1": (f1_train + f1_test) / 2, "edit_distance": 1 - (f1_train + f1_test) / 2}
    return RunRecord(
        f"k{psi}{fold}",
        "psi_s",
        "faithful",
        fold,
        0,
        fold,
        {},
        {"psi_s": psi},
        "done",
        1,
        1.0,
        None,
        1.0,
        {"train": train, "test": test, "mixed": mixed},
    )


def test_the_psi_s_table_gives_mean_and_standard_error_per_value() -> None:
    runs = [_run(1e-4, 0, 0.9, 0.2, 0.4), _run(1e-4, 1, 0.8, 0.4, 0.6), _run(1e-3, 0, 1.0, 0.5, 0.3)]
    rows = psi_s_table(runs)
    assert [r["psi_s"] for r in rows] == [1e-4, 1e-3]
    assert math.isclose(rows[0]["mixed_f1"], 0.575) and math.isclose(rows[0]["mixed_f1_sem"], 0.025)
    assert math.isclose(rows[0]["d_inter"], 0.5) and rows[1]["runs"] == 1 and rows[1]["mixed_f1_sem"] == 0.0
    assert mean_sem([])[2] == 0


def _cosine_runs(rule: dict, epochs: float) -> list[RunRecord]:
    return [
        RunRecord(
            f"c{epochs}{i}",
            "cosine",
            "cosine",
            0,
            i,
            i,
            {},
            {"psi": 0.0, **rule},
            "done",
            1,
            1.0,
            None,
            1.0,
            {"cosine": {"epochs": epochs + i, "d_avg": 1.0, "d_rel": 0.9}},
        )
        for i in range(2)
    ]


def test_the_cosine_table_groups_by_psi_within_one_learning_rule() -> None:
    paper = _cosine_runs({"optimiser": "paper", "zeta_gain": ZETA_GAIN}, 100.0)
    before = _cosine_runs({}, 7.0)  # stored before the rule was a parameter: sign-based RPROP
    (row,) = cosine_table(paper + before)
    assert row["psi"] == 0.0 and row["epochs"] == 100.5 and row["runs"] == 2
    (old,) = cosine_table(paper + before, ("rprop", 1.0))
    assert old["epochs"] == 7.5


def _cosine_run(psi: float, seed: int, d_rel: float, d_avg: float) -> RunRecord:
    rule = {"psi": psi, "optimiser": "paper", "zeta_gain": ZETA_GAIN}
    metrics = {"cosine": {"epochs": 10.0, "d_avg": d_avg, "d_rel": d_rel}}
    return RunRecord(
        f"k{psi}-{seed}", "cosine", "cosine", 0, seed, seed, {}, rule, "done", 1, 2.0, None, 1.0, metrics
    )


def test_the_cosine_table_compares_every_psi_with_psi_zero_on_the_same_seeds() -> None:
    rng = np.random.default_rng(0)
    base = rng.uniform(0.85, 0.95, 30)
    runs = [_cosine_run(0.0, s, base[s], 1.0) for s in range(30)]
    runs += [
        _cosine_run(
            5e-5, s, base[s] + 0.01 + 0.002 * rng.standard_normal(), 0.9 + 0.01 * rng.standard_normal()
        )
        for s in range(30)
    ]
    runs += [
        _cosine_run(2e-4, s, base[s] + 0.002 * rng.standard_normal(), 1.0) for s in range(29)
    ]  # one seed short
    zero, small, large = cosine_table(runs)
    assert "d_rel_vs_0" not in zero and zero["seconds"] == 60.0
    # the spread between seeds (0.03) is far above the effect (0.01): only the pairing sees it
    assert small["d_rel_sem"] > 0.004 and small["d_rel_vs_0"] == pytest.approx(0.01, abs=0.002)
    assert small["d_rel_vs_0_sem"] < 0.001 and small["d_rel_vs_0_p"] < 1e-6
    assert small["d_avg_vs_0"] == pytest.approx(-0.1, abs=0.01)
    assert large["runs"] == 29 and large["d_rel_vs_0_p"] > 0.01
    (_, single) = cosine_table(runs[:1] + [_cosine_run(1e-5, 0, 0.9, 1.0)])
    assert single["d_rel_vs_0_sem"] == 0.0 and math.isnan(single["d_rel_vs_0_p"])  # one pair: no test
