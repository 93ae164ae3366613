"""The preliminary cosine experiment (3.2.2): data, one run, the summary over runs."""

from __future__ import annotations

import json
import math

import pytest
import torch

from model.experiments.cosine import (
    CosineSetup,
    cosine_sequences,
    run_cosine,
    train_cosine_once,
    train_cosine_runs,
)

FAST = CosineSetup(cf=4, threshold=1e-3, max_epochs=25, snapshot_every=5)


def test_four_phase_shifted_contrary_cosines_over_33_steps():
    x = cosine_sequences()
    assert x.shape == (4, 33, 2)
    assert torch.allclose(x[..., 0] + x[..., 1], torch.ones(4, 33))  # contrary: they mirror each other
    assert torch.allclose(x[0, :, 0], 0.5 + 0.5 * torch.cos(torch.linspace(0, 2 * math.pi, 33)))
    assert torch.allclose(x[2, :, 0], x[0, :, 1], atol=1e-6)  # half a period shift swaps the pair
    assert not torch.allclose(x[1], x[3])


def test_without_forcing_the_targets_never_move():
    run = train_cosine_once(0.0, seed=1, setup=FAST)
    assert run.snapshots[0]["targets"] == run.snapshots[-1]["targets"]
    assert run.epochs == FAST.max_epochs or run.converged


def test_strong_forcing_pulls_the_targets_together():
    weak = train_cosine_once(0.0, seed=1, setup=FAST)
    strong = train_cosine_once(0.5, seed=1, setup=FAST)
    assert strong.target_d_avg < weak.target_d_avg


def test_summary_has_mean_and_standard_error_and_is_json():
    result = run_cosine(5e-5, runs=2, seed=0, setup=FAST)
    for key in ("d_avg", "d_rel", "epochs"):
        assert set(result[key]) == {"mean", "se"}
    assert result["d_rel"]["mean"] == pytest.approx(sum(r["d_rel"] for r in result["per_run"]) / 2)
    json.dumps(result)


def test_runs_learning_together_are_the_runs_learning_alone():
    alone = [train_cosine_once(2e-3, seed, FAST) for seed in (3, 4)]
    together = train_cosine_runs(2e-3, [3, 4], FAST)
    for a, t in zip(alone, together, strict=True):
        assert a.epochs == t.epochs and a.converged == t.converged
        assert a.d_rel == pytest.approx(t.d_rel, abs=1e-3) and a.target_d_avg == pytest.approx(
            t.target_d_avg, abs=1e-4
        )
