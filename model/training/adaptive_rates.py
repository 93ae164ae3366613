"""The paper's learning rule (3.1.3-3.1.4): every element learns by its own rate times its gradient.

    w_ij <- w_ij - eta_ij dE/dw_ij                                     eq. (7)
    b_i  <- b_i  - beta_i dE/db_i                                      eq. (8)
    c_0,i <- c_0,i - zeta_i dE/dc_0,i                                  eq. (9)
    zeta_i = zeta_gain * mean_{j in Cf u Cs} eta_ij                    eq. (10)
    c_T,i <- c_T,i - psi zeta_i dE/dc_T,i                              eq. (12)

The rates eta and beta are adapted by RPROP's sign rule (Riedmiller & Braun 1993, "an adaptation
of RPROP that makes use of different individual learning rates"): while an element's gradient
keeps its sign its rate grows by xi+, when the sign flips it shrinks by xi-, always within
[eta_min, eta_max] (Table 1: 1.01, 0.96, [1e-6, 1], eta^0 = beta^0 = zeta^0 = 0.05). Unlike plain
RPROP (`torch.optim.Rprop`), the step is the rate times the gradient, not the rate times its sign.

The initial (eq. 9) and final (eq. 12) Csc states have no rates of their own: eq. (10) makes zeta_i
proportional to the mean rate of unit i's weights from the Cf and Cs layers. The paper does not
give the constant of proportion; `zeta_gain` names it (docs/experiments/faithful.md calibrates it
on Fig. 3). Before the first step of the weights, their rates are eta^0, so zeta starts at
zeta_gain * eta^0.

A parameter group is either ordinary (its elements get their own adapted rates) or a context group
``{"params": [c], "context_of": net, "scale": psi}``, whose rate is zeta of `net` (an MTRNN whose
weight matrix is in the same optimiser) times `scale` (1 for c_0, psi for c_T).
"""

from __future__ import annotations

from collections.abc import Iterable

import torch
from torch import Tensor


class AdaptiveRates(torch.optim.Optimizer):
    """Per-element adaptive rates applied to the gradient (module docstring, eqs. 7-10, 12)."""

    def __init__(
        self,
        params: Iterable,
        lr: float = 0.05,
        etas: tuple[float, float] = (0.96, 1.01),
        rate_bounds: tuple[float, float] = (1e-6, 1.0),
        zeta_gain: float = 1.0,
    ) -> None:
        if not 0.0 < etas[0] < 1.0 < etas[1]:
            raise ValueError(f"need 0 < xi- < 1 < xi+, got {etas}")
        if not 0.0 < rate_bounds[0] <= lr <= rate_bounds[1]:
            raise ValueError(f"need eta_min <= eta^0 <= eta_max, got {lr} and {rate_bounds}")
        defaults = {"lr": lr, "etas": etas, "rate_bounds": rate_bounds, "zeta_gain": zeta_gain}
        defaults |= {"context_of": None, "scale": 1.0}
        super().__init__(params, defaults)

    def rates(self, p: Tensor) -> Tensor:
        """The adapted per-element rates of `p` (eta^0 everywhere before its first step)."""
        state = self.state[p]
        if "rate" not in state:
            group = next(g for g in self.param_groups if any(q is p for q in g["params"]))
            return torch.full_like(p, group["lr"])
        return state["rate"]

    def zeta(self, net: torch.nn.Module, zeta_gain: float) -> Tensor:
        """eq. (10): zeta_i [csc] ([R, csc] for stacked nets) from the rates of Csc unit i's weights
        from Cf and Cs units."""
        eta = self.rates(net.weight)  # [N, N], or [R, N, N] for R stacked nets
        return zeta_gain * eta[..., net.csc_slice, net.cfg.io :].mean(dim=-1)

    @torch.no_grad()
    def step(self, closure=None):  # noqa: D401 - the Optimizer API
        loss = None
        if closure is not None:
            with torch.enable_grad():
                loss = closure()
        ordinary = [g for g in self.param_groups if g["context_of"] is None]
        for group in ordinary:  # first the rates of weights and biases (eqs. 7-8) ...
            for p in group["params"]:
                if p.grad is not None:
                    self._adapt_and_step(p, group)
        for group in self.param_groups:  # ... then the contexts, whose rates follow them (eq. 10)
            if group["context_of"] is None:
                continue
            zeta = group["scale"] * self.zeta(group["context_of"], group["zeta_gain"])
            for p in group["params"]:
                if p.grad is not None:
                    p.sub_(zeta.unsqueeze(-2) * p.grad)  # eqs. (9), (12); p is [..., B, csc]
        return loss

    def _adapt_and_step(self, p: Tensor, group: dict) -> None:
        """RPROP's sign rule on the element's rate, then rate times gradient (eqs. 7-8)."""
        state = self.state[p]
        if "rate" not in state:
            state["rate"] = torch.full_like(p, group["lr"])
            state["previous"] = torch.zeros_like(p)
        xi_minus, xi_plus = group["etas"]
        lo, hi = group["rate_bounds"]
        agreement = p.grad * state["previous"]
        factor = torch.where(agreement > 0, xi_plus, torch.where(agreement < 0, xi_minus, 1.0))
        state["rate"].mul_(factor).clamp_(lo, hi)
        state["previous"].copy_(p.grad)
        p.sub_(state["rate"] * p.grad)
