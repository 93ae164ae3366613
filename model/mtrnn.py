"""The multiple timescale recurrent neural network (paper 3.1-3.2, eqs. 2-5 and 11-12).

One MTRNN has three horizontal layers, IO, context-fast (Cf) and context-slow (Cs), each with its
own timescale tau. The first |Csc| units of Cs are the context-controlling units. Connectivity is
adjacent only: IO<->Cf, Cf<->Cs and recurrence within each layer; IO and Cs never connect.

The same network is used two ways:
- with *context bias* (MTRNN_a): the Csc internal state at t = 0 is a context c_0 from which the
  network generates a sequence closed-loop (`generate`);
- with *context abstraction* (MTRNN_s, MTRNN_v): the network reads a sequence and its Csc internal
  state at the final step T is the abstracted context c_T (`abstract`).

Implementation (the "fused" form, ~2x one nn.Linear per block, see benchmarks/train_speed.py):
one masked dense weight matrix for all blocks with 1/tau folded in, and every input that does not
depend on the network's own state (the encoders' sensory input, the generator's teacher part of
eq. 5) projected for all time steps at once.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from model.config import KAPPA_H, KAPPA_W, MTRNNConfig


def scaled_logistic(z: Tensor) -> Tensor:
    """The paper's sigmoid (3.4.3): a logistic of slope kappa_w stretched to (-kappa_h, 1 + kappa_h).

    Our reading of "kappa_h = 0.35795 for range, kappa_w = 0.92 for slope":
    f(z) = (1 + 2 kappa_h) / (1 + exp(-kappa_w z)) - kappa_h. The stretch 1 + 2 kappa_h = 1.7159 is
    LeCun's constant, so targets 0 and 1 sit on the steep part of f, as LeCun et al. (1998) advise.
    """
    return (1.0 + 2.0 * KAPPA_H) * torch.sigmoid(KAPPA_W * z) - KAPPA_H


def scaled_logistic_inverse(y: Tensor) -> Tensor:
    """z such that scaled_logistic(z) = y, for y in (-kappa_h, 1 + kappa_h)."""
    p = (y + KAPPA_H) / (1.0 + 2.0 * KAPPA_H)
    return torch.logit(p) / KAPPA_W


def connectivity_mask(cfg: MTRNNConfig) -> Tensor:
    """mask[i, j] = 1 where unit j projects to unit i: adjacent layers and within-layer recurrence."""
    layer = torch.cat([torch.full((n,), k) for k, n in enumerate((cfg.io, cfg.cf, cfg.cs))])
    return ((layer[:, None] - layer[None, :]).abs() <= 1).float()


class MTRNN(nn.Module):
    """One MTRNN layer stack: IO, Cf, Cs with per-layer timescales (eqs. 2-5)."""

    def __init__(self, cfg: MTRNNConfig, generator: torch.Generator | None = None) -> None:
        super().__init__()
        self.cfg = cfg
        n = cfg.size

        def uniform(*shape: int) -> Tensor:
            return (torch.rand(*shape, generator=generator) * 2 - 1) * cfg.weight_init

        self.weight = nn.Parameter(uniform(n, n))  # w_ij: from unit j to unit i
        self.bias = nn.Parameter(uniform(n))  # b_i
        self.register_buffer("mask", connectivity_mask(cfg))
        tau = torch.cat(
            [
                torch.full((cfg.io,), float(cfg.tau_io)),
                torch.full((cfg.cf,), float(cfg.tau_cf)),
                torch.full((cfg.cs,), float(cfg.tau_cs)),
            ]
        )
        self.register_buffer("tau", tau)

    @property
    def csc_slice(self) -> slice:
        """The Csc units: the first |Csc| units of the Cs layer."""
        start = self.cfg.io + self.cfg.cf
        return slice(start, start + self.cfg.csc)

    @property
    def csc_bias(self) -> Tensor:
        return self.bias[self.csc_slice]

    def masked_weight(self) -> Tensor:
        return self.weight * self.mask

    def activation(self, z: Tensor) -> Tensor:
        """eq. (4): softmax on MTRNN_a's IO (eq. 21), the scaled logistic everywhere else."""
        io = self.cfg.io
        if self.cfg.io_activation == "softmax":
            return torch.cat([torch.softmax(z[..., :io], dim=-1), scaled_logistic(z[..., io:])], dim=-1)
        return scaled_logistic(z)

    def _scaled_parameters(self) -> tuple[Tensor, Tensor, Tensor]:
        """eq. (3) with 1/tau folded in once per pass: z_t = decay * z_{t-1} + x_t @ W' + b', where
        W' = (w / tau_i)^T (masked) and b' = b / tau. Fewer operations per step than
        applying 1/tau to every drive."""
        inv_tau = 1.0 / self.tau
        return (self.masked_weight() * inv_tau[:, None]).T, self.bias * inv_tau, 1.0 - inv_tau

    def initial_state(self, batch: int, c0: Tensor | None = None) -> Tensor:
        """z_0: the Csc units hold c_0 (eq. 3, t = 0), every other unit starts at 0."""
        z = torch.zeros(batch, self.cfg.size, dtype=self.weight.dtype, device=self.weight.device)
        if c0 is not None:
            z = z.clone()
            z[:, self.csc_slice] = c0
        return z

    def abstract(self, inputs: Tensor, lengths: Tensor | None = None, return_states: bool = False):
        """Context abstraction (3.2): read `inputs` [B, T, io] and return c_T, the Csc internal
        states at each sequence's final step [B, csc] (with all internal states [B, T, N] if asked).

        eq. (2): IO units take the sensory input x*_t; every other unit takes y_{t-1}.
        """
        batch, steps, _ = inputs.shape
        io = self.cfg.io
        w, b, decay = self._scaled_parameters()
        # The input projection for all steps at once; unbind (not drive_in[:, t]) so that BPTT
        # gathers the per-step gradients in one stack instead of one full-size buffer per step.
        drive_in = (inputs @ w[:io] + b).unbind(1)
        w_rec = w[io:].contiguous()
        z = self.initial_state(batch)
        y_rec = self.activation(z)[:, io:]
        states = []
        for t in range(steps):
            z = torch.addmm(decay * z + drive_in[t], y_rec, w_rec)  # eq. (3)
            y_rec = scaled_logistic(z[:, io:])  # eq. (4): only Cf and Cs feed the next step
            states.append(z if return_states else z[:, self.csc_slice])
        trajectory = torch.stack(states, dim=1)
        last = (lengths.long() - 1) if lengths is not None else torch.full((batch,), steps - 1)
        rows = torch.arange(batch)
        if not return_states:
            return trajectory[rows, last]
        return trajectory[rows, last, self.csc_slice], trajectory

    def generate(
        self,
        c0: Tensor,
        steps: int,
        teacher: Tensor | None = None,
        alpha: float = 0.0,
        return_states: bool = False,
    ):
        """Context bias (3.1.1): from c_0 [B, csc] produce IO activity y_0..y_{steps-1} [B, steps, io].

        eq. (5): the IO input is (alpha) y*_{t-1} + (1 - alpha) y_{t-1}; with alpha = 0 (or no
        teacher) the generation is closed-loop.
        """
        io = self.cfg.io
        w, b, decay = self._scaled_parameters()
        if teacher is not None and alpha > 0.0:
            # eq. (5) split by linearity: the teacher's part alpha y*_{t-1} W' is projected for all
            # steps at once, the network's own (1 - alpha) y_{t-1} is folded into the IO rows of W'.
            drive = (alpha * teacher[:, : steps - 1] @ w[:io] + b).unbind(1)
            w = torch.cat([(1.0 - alpha) * w[:io], w[io:]])
        else:
            drive = (b,) * (steps - 1)
        z = self.initial_state(c0.shape[0], c0)
        y = self.activation(z)
        outputs, states = [y[:, :io]], [z]
        for t in range(1, steps):
            z = torch.addmm(decay * z + drive[t - 1], y, w)  # eqs. (3), (5)
            y = self.activation(z)
            outputs.append(y[:, :io])
            if return_states:
                states.append(z)
        activity = torch.stack(outputs, dim=1)
        return (activity, torch.stack(states, dim=1)) if return_states else activity


def kl_divergence(target: Tensor, output: Tensor, eps: float = 1e-8) -> Tensor:
    """KLD between desired and produced softmax activity (3.1.3), summed over units and steps t >= 1
    (eqs. 7-8 accumulate the error over the sequence) and averaged over sequences (summed, MTRNN_a
    diverges at its first step: docs/experiments/faithful.md). Step 0 is the fixed initial state
    and carries no error."""
    t, o = target[:, 1:], output[:, 1:]
    return (t * (torch.log(t + eps) - torch.log(o + eps))).sum(dim=(1, 2)).mean()


def context_abstraction_loss(net: MTRNN, c_t_produced: Tensor, c_t_target: Tensor, psi: float) -> Tensor:
    """LMS on the final Csc states with self-organisation forcing (eqs. 11-12), averaged over
    sequences as `kl_divergence`.

    eq. (11): the weights learn from (1 - psi) of the error between y_T = f(z_T) and f(c_T + b).
    eq. (12): the targets c_T move along the same error, descending it (towards the network's
    activity). The gradient reaching c_T is the whole error's; its psi * zeta step is the
    optimiser's (`model.training.common.make_optimiser`: a context group scaled by psi).
    """
    bias = net.csc_bias.detach()
    produced = scaled_logistic(c_t_produced)
    weights_part = 0.5 * ((produced - scaled_logistic(c_t_target.detach() + bias)) ** 2).sum(dim=1)
    targets_part = 0.5 * ((produced.detach() - scaled_logistic(c_t_target + bias)) ** 2).sum(dim=1)
    return ((1.0 - psi) * weights_part + targets_part).mean()
