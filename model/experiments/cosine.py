"""The preliminary experiment of 3.2.2 (Fig. 3): self-organisation of abstracted contexts.

Four sequences of two contrary cosines over 33 steps, differing only in phase, are read by an
MTRNN with context abstraction. Its final Csc targets c_T start random in [-1, 1] and move with
the psi-scaled RPROP step of eq. (12) while the weights learn from (1 - psi) of the error
(eq. 11). After training, the spread of the abstracted contexts is measured by d_avg and d_rel
(eqs. 13-15).

The paper gives neither the network's size nor its stopping rule for this experiment. Its
Fig. 3(c-f) plots the patterns in a plane and note 5 discusses four sequences on two Csc units,
so we use |Csc| = 2 (|Cs| = 4), |Cf| = 10, two IO units, timescales 2 / 5 / 16, Table 1's RPROP
settings, and train until the LMS error of eq. (11) is below `threshold` or `max_epochs`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import torch
from torch import Tensor, nn

from model.config import MTRNNConfig, TrainingConfig
from model.metrics import d_avg, d_rel, mean_sem
from model.mtrnn import MTRNN, context_abstraction_loss, scaled_logistic
from model.training.common import make_optimiser

STEPS = 33
PHASES = (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi)
PSIS = (0.0, 1e-5, 5e-5, 2e-4)


@dataclass(frozen=True)
class CosineSetup:
    """Network and training of the experiment (module docstring)."""

    cf: int = 10
    cs: int = 4
    tau_io: float = 2
    tau_cf: float = 5
    tau_cs: float = 16
    threshold: float = 1e-5  # mean LMS error per sequence at the final step, 0.5 * ||y_T - f(c_T + b)||^2
    max_epochs: int = 2000
    snapshot_every: int = 25  # epochs between two recorded Csc snapshots

    def network(self) -> MTRNNConfig:
        return MTRNNConfig(
            io=2, cf=self.cf, cs=self.cs, tau_io=self.tau_io, tau_cf=self.tau_cf, tau_cs=self.tau_cs
        )


def cosine_sequences(steps: int = STEPS, phases: tuple[float, ...] = PHASES) -> Tensor:
    """[4, 33, 2]: cos and its contrary -cos over one period, phase-shifted, mapped to [0, 1]."""
    t = torch.linspace(0.0, 2.0 * math.pi, steps)
    seqs = [torch.stack([0.5 + 0.5 * torch.cos(t + p), 0.5 - 0.5 * torch.cos(t + p)], dim=-1) for p in phases]
    return torch.stack(seqs)


def lms_error(net: MTRNN, c_t_produced: Tensor, c_t_target: Tensor) -> float:
    """The error of eq. (11) without the psi split: mean over sequences of 0.5 ||y_T - f(c_T + b)||^2."""
    diff = scaled_logistic(c_t_produced) - scaled_logistic(c_t_target + net.csc_bias.detach())
    return float(0.5 * (diff**2).sum(dim=1).mean())


@dataclass
class CosineRun:
    epochs: int  # epochs until the error fell below the threshold (max_epochs if it never did)
    converged: bool
    d_avg: float  # of the abstracted contexts (the network's final Csc states)
    d_rel: float
    target_d_avg: float  # of the learned targets c_T
    target_d_rel: float
    snapshots: list[dict]  # {"epoch", "csc": [[..], ...] the network's c_T, "targets": ...}


def train_cosine_once(
    psi: float,
    seed: int,
    setup: CosineSetup = CosineSetup(),
    progress: Callable[[dict], None] | None = None,
) -> CosineRun:
    """One run: a fresh network (seeded) abstracting the four cosine sequences."""
    torch.manual_seed(seed)
    g = torch.Generator().manual_seed(seed)
    net = MTRNN(setup.network(), g)
    inputs = cosine_sequences()
    c_t = nn.Parameter(
        (torch.rand(len(inputs), net.cfg.csc, generator=g) * 2 - 1) * 1.0, requires_grad=psi > 0
    )
    optimiser = make_optimiser(
        [{"params": list(net.parameters())}, {"params": [c_t], "scale": psi}], TrainingConfig()
    )
    snapshots: list[dict] = []
    epoch, converged = 0, False
    while epoch < setup.max_epochs:
        optimiser.zero_grad()
        produced = net.abstract(inputs)
        error = lms_error(net, produced.detach(), c_t.detach())
        if epoch % setup.snapshot_every == 0 or error < setup.threshold:
            snap = {"epoch": epoch, "error": error, "csc": produced.tolist(), "targets": c_t.tolist()}
            snapshots.append(snap)
            if progress is not None:
                progress({"stage": "cosine", "psi": psi, "seed": seed, "loss": error, **snap})
        if error < setup.threshold:
            converged = True
            break
        context_abstraction_loss(net, produced, c_t, psi).backward()
        optimiser.step()
        epoch += 1
    with torch.no_grad():
        final = net.abstract(inputs).numpy()
    targets = c_t.detach().numpy()
    return CosineRun(epoch, converged, d_avg(final), d_rel(final), d_avg(targets), d_rel(targets), snapshots)


def _mean_se(values: list[float]) -> dict[str, float]:
    mean, se, _ = mean_sem(values)
    return {"mean": mean, "se": se}


def run_cosine(
    psi: float,
    runs: int = 10,
    seed: int = 0,
    progress: Callable[[dict], None] | None = None,
    setup: CosineSetup = CosineSetup(),
) -> dict:
    """`runs` seeded runs (seeds seed .. seed + runs - 1, the same for every psi, so psi values
    are compared on identical initialisations). JSON-serialisable summary with per-run results and
    Csc snapshots for a live plot."""
    results = [train_cosine_once(psi, seed + r, setup, progress) for r in range(runs)]
    return {
        "psi": psi,
        "runs": runs,
        "converged": sum(r.converged for r in results),
        "epochs": _mean_se([r.epochs for r in results]),
        "d_avg": _mean_se([r.d_avg for r in results]),
        "d_rel": _mean_se([r.d_rel for r in results]),
        "target_d_avg": _mean_se([r.target_d_avg for r in results]),
        "target_d_rel": _mean_se([r.target_d_rel for r in results]),
        "per_run": [
            {k: v for k, v in r.__dict__.items() if k != "snapshots"} | {"seed": seed + i}
            for i, r in enumerate(results)
        ],
        "snapshots": [r.snapshots for r in results],
    }
