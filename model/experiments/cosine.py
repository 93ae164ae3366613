"""The preliminary experiment of 3.2.2 (Fig. 3): self-organisation of abstracted contexts.

Four sequences of two contrary cosines over 33 steps, differing only in phase, are read by an
MTRNN with context abstraction. Its final Csc targets c_T start random in [-1, 1] and move with
the psi-scaled RPROP step of eq. (12) while the weights learn from (1 - psi) of the error
(eq. 11). After training, the spread of the abstracted contexts is measured by d_avg and d_rel
(eqs. 13-15).

The paper gives neither the network's size nor its stopping rule for this experiment. Its
Fig. 3(c-f) plots the patterns in a plane and note 5 discusses four sequences on two Csc units,
so we use |Csc| = 2 (|Cs| = 4), |Cf| = 10, two IO units, timescales 2 / 5 / 16, Table 1's rates
with the paper's learning rule (`model.training.adaptive_rates`; the errors of the four sequences
summed), and train until the LMS error of eq. (11) is below `threshold` or `max_epochs`. This is
the figure that calibrates eq. (10)'s `zeta_gain` (docs/experiments/faithful.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import torch
from torch import Tensor, nn

from model.config import ZETA_GAIN, MTRNNConfig, TrainingConfig
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
    max_epochs: int = 20000
    snapshot_every: int = 25  # epochs between two recorded Csc snapshots
    optimiser: str = "paper"  # a `model.config.LEARNING_RULES` rule
    zeta_gain: float = ZETA_GAIN  # eq. (10)'s constant

    def training(self) -> TrainingConfig:
        return TrainingConfig(optimiser=self.optimiser, zeta_gain=self.zeta_gain)

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
    training = setup.training()
    optimiser = make_optimiser(
        [{"params": list(net.parameters())}, {"params": [c_t], "scale": psi, "context_of": net}], training
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


class _Abstraction(nn.Module):
    """`MTRNN.abstract` as a module's forward, so `torch.func` can map it over stacked weights."""

    def __init__(self, net: MTRNN) -> None:
        super().__init__()
        self.net = net

    def forward(self, inputs: Tensor) -> Tensor:
        return self.net.abstract(inputs)


@dataclass
class _Stacked:
    """What `AdaptiveRates.zeta` reads of a net (eq. 10), for R nets' weights stacked [R, N, N]."""

    weight: Tensor
    csc_slice: slice
    cfg: MTRNNConfig


def train_cosine_runs(
    psi: float | Sequence[float],
    seeds: Sequence[int],
    setup: CosineSetup = CosineSetup(),
    zeta_gains: Sequence[float] | None = None,
) -> list[CosineRun]:
    """`train_cosine_once` for several seeds at once: the R networks (each initialised exactly as
    its single run) are stacked and run as one vectorised pass (`torch.func.vmap`), and a run that
    has converged stops learning (zero gradients leave its weights and rates unchanged). The same
    computation as one run at a time but for float rounding (which grows over thousands of epochs,
    so runs agree in distribution, not digit for digit), an order of magnitude faster. Each run's
    one snapshot is its final state.

    `psi` is one value or one per run; under the paper's rule `zeta_gains` (one per run, default
    the setup's) lets one pass calibrate eq. (10)'s constant: run r's c_T steps by
    psi_r * zeta_gains_r * mean eta (eqs. 10, 12)."""
    psis = [float(psi)] * len(seeds) if isinstance(psi, (int, float)) else [float(p) for p in psi]
    gains = [setup.zeta_gain] * len(seeds) if zeta_gains is None else [float(g) for g in zeta_gains]
    if not len(psis) == len(gains) == len(seeds):
        raise ValueError("need one psi and one zeta gain per seed")
    if setup.optimiser != "paper" and (len(set(psis)) > 1 or zeta_gains is not None):
        raise ValueError("per-run psi or zeta gains need the paper's rule (a step size per group otherwise)")
    nets, targets = [], []
    for seed in seeds:
        torch.manual_seed(seed)
        g = torch.Generator().manual_seed(seed)
        nets.append(MTRNN(setup.network(), g))
        targets.append((torch.rand(len(PHASES), nets[-1].cfg.csc, generator=g) * 2 - 1) * 1.0)
    base = _Abstraction(nets[0])
    weight = nn.Parameter(torch.stack([n.weight.detach() for n in nets]))
    bias = nn.Parameter(torch.stack([n.bias.detach() for n in nets]))
    c_t = nn.Parameter(torch.stack(targets), requires_grad=max(psis) > 0)
    stacked = _Stacked(weight, nets[0].csc_slice, nets[0].cfg)
    if setup.optimiser == "paper":  # psi_r * gain_r per run, the gain folded into the scale
        training = replace(setup.training(), zeta_gain=1.0)
        scale: float | Tensor = torch.tensor([p * g for p, g in zip(psis, gains, strict=True)])[:, None]
    else:
        training, scale = setup.training(), psis[0]
    optimiser = make_optimiser(
        [{"params": [weight, bias]}, {"params": [c_t], "scale": scale, "context_of": stacked}], training
    )
    abstract = torch.func.vmap(
        lambda w, b, x: torch.func.functional_call(base, {"net.weight": w, "net.bias": b}, (x,)),
        in_dims=(0, 0, None),
    )
    inputs, csc = cosine_sequences(), nets[0].csc_slice
    epochs = torch.full((len(seeds),), setup.max_epochs)
    active = torch.ones(len(seeds), dtype=torch.bool)
    for epoch in range(setup.max_epochs + 1):
        produced = abstract(weight, bias, inputs)  # [R, 4, csc]
        target = scaled_logistic(c_t + bias[:, None, csc])
        error = 0.5 * ((scaled_logistic(produced) - target) ** 2).sum(-1).mean(-1)  # per run, as lms_error
        done = active & (error.detach() < setup.threshold)
        epochs[done], active = epoch, active & ~done
        if not active.any() or epoch == setup.max_epochs:
            break
        optimiser.zero_grad()
        loss = sum(
            context_abstraction_loss(_view(nets[0], bias[r]), produced[r], c_t[r], psis[r])
            for r in range(len(seeds))
            if active[r]
        )
        loss.backward()
        optimiser.step()
    with torch.no_grad():
        final = abstract(weight, bias, inputs).numpy()
    ends = c_t.detach().numpy()
    return [
        CosineRun(
            int(epochs[r]),
            bool(~active[r]),
            d_avg(final[r]),
            d_rel(final[r]),
            d_avg(ends[r]),
            d_rel(ends[r]),
            [{"epoch": int(epochs[r]), "csc": final[r].tolist(), "targets": ends[r].tolist()}],
        )
        for r in range(len(seeds))
    ]


def _view(net: MTRNN, bias: Tensor) -> _BiasView:
    return _BiasView(bias[net.csc_slice])


@dataclass
class _BiasView:
    """The one thing `context_abstraction_loss` reads of a net: its Csc biases."""

    csc_bias: Tensor


def _mean_se(values: list[float]) -> dict[str, float]:
    mean, se, _ = mean_sem(values)
    return {"mean": mean, "se": se}


def run_cosine(psi: float, runs: int = 10, seed: int = 0, setup: CosineSetup = CosineSetup()) -> dict:
    """`runs` seeded runs (seeds seed .. seed + runs - 1, the same for every psi, so psi values
    are compared on identical initialisations), learning together (`train_cosine_runs`).
    JSON-serialisable summary with per-run results."""
    results = train_cosine_runs(psi, list(range(seed, seed + runs)), setup)
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
    }
