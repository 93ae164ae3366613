"""Training speed at the paper's sizes (Table 1, 128 sequences).

1. ms per full-batch epoch (forward, BPTT, one RPROP step) of each net: the fused MTRNN of
   `model.mtrnn` (one masked dense matrix, the encoders' input projection for all steps at once)
   against a straightforward per-block reference written here (one nn.Linear per connected block
   pair, evaluated per step), with the ratio.
2. Wall time of one whole training per mode (`model.training.MODES`) on fold 0 of the corpus
   (faithful and end_to_end by default), unless --skip-training.

Run:  .venv/bin/python benchmarks/train_speed.py [--epochs 10] [--skip-training] [--json]
The machine is shared: note the load average printed at the start when reading the numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np
import torch
from torch import Tensor, nn

from model.config import MTRNNConfig, MultiMTRNNConfig, TrainingConfig
from model.mtrnn import MTRNN, context_abstraction_loss, kl_divergence, scaled_logistic
from model.training.common import make_optimiser

LAYERS = ("io", "cf", "cs")
CONNECTED = [(d, s) for d in range(3) for s in range(3) if abs(d - s) <= 1]  # adjacent + recurrence


class BlockMTRNN(nn.Module):
    """Reference MTRNN: one nn.Linear per connected (destination, source) layer pair, per step."""

    def __init__(self, cfg: MTRNNConfig) -> None:
        super().__init__()
        self.cfg = cfg
        sizes = (cfg.io, cfg.cf, cfg.cs)
        self.sizes = sizes
        self.links = nn.ModuleDict(
            {f"{LAYERS[d]}_{LAYERS[s]}": nn.Linear(sizes[s], sizes[d], bias=(d == s)) for d, s in CONNECTED}
        )
        self.taus = (cfg.tau_io, cfg.tau_cf, cfg.tau_cs)
        for p in self.parameters():
            nn.init.uniform_(p, -cfg.weight_init, cfg.weight_init)

    def f(self, layer: int, z: Tensor) -> Tensor:
        if layer == 0 and self.cfg.io_activation == "softmax":
            return torch.softmax(z, dim=-1)
        return scaled_logistic(z)

    def step(self, z: list[Tensor], x: list[Tensor]) -> list[Tensor]:
        out = []
        for d in range(3):
            drive = sum(self.links[f"{LAYERS[d]}_{LAYERS[s]}"](x[s]) for s in range(3) if abs(d - s) <= 1)
            out.append((1 - 1 / self.taus[d]) * z[d] + drive / self.taus[d])
        return out

    def abstract(self, inputs: Tensor, lengths: Tensor) -> Tensor:
        batch = inputs.shape[0]
        z = [torch.zeros(batch, n) for n in self.sizes]
        y = [self.f(k, z[k]) for k in range(3)]
        finals = []
        for t in range(inputs.shape[1]):
            z = self.step(z, [inputs[:, t], y[1], y[2]])
            y = [self.f(k, z[k]) for k in range(3)]
            finals.append(z[2][:, : self.cfg.csc])
        stacked = torch.stack(finals, dim=1)
        return stacked[torch.arange(batch), lengths - 1]

    def generate(self, c0: Tensor, steps: int, teacher: Tensor, alpha: float) -> Tensor:
        batch = c0.shape[0]
        z = [torch.zeros(batch, n) for n in self.sizes]
        z[2] = torch.cat([c0, torch.zeros(batch, self.sizes[2] - c0.shape[1])], dim=1)
        y = [self.f(k, z[k]) for k in range(3)]
        outputs = [y[0]]
        for t in range(1, steps):
            x_io = alpha * teacher[:, t - 1] + (1 - alpha) * y[0]
            z = self.step(z, [x_io, y[1], y[2]])
            y = [self.f(k, z[k]) for k in range(3)]
            outputs.append(y[0])
        return torch.stack(outputs, dim=1)


def _time_epochs(epoch, epochs: int, warmup: int = 2) -> float:
    for _ in range(warmup):
        epoch()
    times = []
    for _ in range(epochs):
        start = time.perf_counter()
        epoch()
        times.append(time.perf_counter() - start)
    return 1000 * statistics.median(times)


def bench_nets(epochs: int, seed: int = 0) -> dict:
    g = torch.Generator().manual_seed(seed)
    rng = np.random.default_rng(seed)
    cfg = MultiMTRNNConfig()
    training = TrainingConfig()
    n = 128
    results = {}
    # auditory: utterances ~50 steps, softmax targets, teacher forcing 0.1, KLD
    steps_a = 50
    target = torch.softmax(3 * torch.randn(n, steps_a, cfg.auditory.io, generator=g), dim=-1)
    for kind, net in (("fused", MTRNN(cfg.auditory, g)), ("per_block", BlockMTRNN(cfg.auditory))):
        c0 = nn.Parameter(torch.zeros(n, cfg.auditory.csc))
        opt = make_optimiser([{"params": [*net.parameters(), c0]}], training)

        def epoch(net=net, c0=c0, opt=opt):
            opt.zero_grad()
            kl_divergence(target, net.generate(c0, steps_a, target, 0.1)).backward()
            opt.step()

        results.setdefault("auditory", {})[kind] = _time_epochs(epoch, epochs)
    # encoders: perception 60-120 steps, padded, LMS on the final Csc (eq. 11)
    for name, net_cfg, psi in (
        ("somatosensory", cfg.somatosensory, training.psi_s),
        ("visual", cfg.visual, training.psi_v),
    ):
        lengths = torch.as_tensor(rng.integers(60, 121, size=n))
        x = torch.rand(n, int(lengths.max()), net_cfg.io, generator=g)
        for kind, net in (("fused", MTRNN(net_cfg, g)), ("per_block", BlockMTRNN(net_cfg))):
            c_t = nn.Parameter(torch.rand(n, net_cfg.csc, generator=g) * 2 - 1)
            opt = make_optimiser(
                [{"params": list(net.parameters())}, {"params": [c_t], "scale": psi}], training
            )
            bias_net = net if isinstance(net, MTRNN) else MTRNN(net_cfg)

            def epoch(net=net, c_t=c_t, opt=opt, x=x, lengths=lengths, bias_net=bias_net, psi=psi):
                opt.zero_grad()
                context_abstraction_loss(bias_net, net.abstract(x, lengths), c_t, psi).backward()
                opt.step()

            results.setdefault(name, {})[kind] = _time_epochs(epoch, epochs)
    for r in results.values():
        r["speedup"] = r["per_block"] / r["fused"]
    return results


def bench_training(modes: list[str], corpus_path: str | None = None, fold: int = 0, seed: int = 0) -> dict:
    from data.corpus import load_corpus
    from model.experiments.splits import scene_split
    from model.training import train

    corpus = load_corpus(corpus_path)
    data = corpus.training_data()
    train_idx, _ = scene_split(data.ids, fold)
    out = {}
    for mode in modes:
        start = time.perf_counter()
        trained = train(data.subset(train_idx), mode=mode, seed=seed)
        out[mode] = {"seconds": time.perf_counter() - start, "stages": trained.meta.get("seconds")}
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=int, default=10, help="timed epochs per net (median reported)")
    parser.add_argument("--skip-training", action="store_true", help="only the per-epoch timings")
    parser.add_argument("--modes", nargs="+", default=["faithful", "end_to_end"], help="modes to time")
    parser.add_argument("--corpus", default=None, help="corpus .npz (default: the shipped one)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    torch.set_num_threads(1)
    report: dict = {"load_average_before": os.getloadavg(), "threads": 1}
    report["epoch_ms"] = bench_nets(args.epochs)
    if not args.skip_training:
        from model.training import MODES

        modes = [m for m in args.modes if m in MODES]
        report["training"] = bench_training(modes, args.corpus)
    report["load_average_after"] = os.getloadavg()
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"load average before: {report['load_average_before']}  (2 shared cores; 1 torch thread)")
    print(f"{'net':14s} {'fused ms':>9s} {'per-block ms':>13s} {'speedup':>8s}")
    for name, r in report["epoch_ms"].items():
        print(f"{name:14s} {r['fused']:9.1f} {r['per_block']:13.1f} {r['speedup']:7.2f}x")
    for mode, r in report.get("training", {}).items():
        print(f"whole training, {mode}, fold 0: {r['seconds']:.1f} s wall  stages: {r['stages']}")
    print(f"load average after: {report['load_average_after']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
