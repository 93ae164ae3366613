"""The paper's learning rule (eqs. 7-10, 12): rates adapted by the sign rule, applied to the gradient."""

from __future__ import annotations

import pytest
import torch
from torch import nn

from model.config import MTRNNConfig, TrainingConfig
from model.mtrnn import MTRNN
from model.training.adaptive_rates import AdaptiveRates
from model.training.common import make_optimiser


def _step(optimiser: torch.optim.Optimizer, p: nn.Parameter, grad: list[float]) -> None:
    optimiser.zero_grad()
    p.grad = torch.tensor(grad)
    optimiser.step()


def test_the_step_is_the_rate_times_the_gradient_not_its_sign():
    p = nn.Parameter(torch.zeros(2))
    optimiser = AdaptiveRates([p], lr=0.05)
    _step(optimiser, p, [2.0, -0.5])
    assert torch.allclose(p.detach(), torch.tensor([-0.1, 0.025]))  # eq. (7): -eta * dE/dw


def test_rates_grow_while_the_sign_holds_and_shrink_when_it_flips_within_bounds():
    p = nn.Parameter(torch.zeros(2))
    optimiser = AdaptiveRates([p], lr=0.05, etas=(0.96, 1.01), rate_bounds=(1e-6, 0.0506))
    _step(optimiser, p, [1.0, 1.0])  # first step: no previous gradient, rates stay eta^0
    _step(optimiser, p, [1.0, -1.0])
    assert torch.allclose(optimiser.rates(p), torch.tensor([0.0505, 0.048]))
    _step(optimiser, p, [1.0, 1.0])
    assert torch.allclose(optimiser.rates(p), torch.tensor([0.0506, 0.04608]))  # capped at eta_max
    _step(optimiser, p, [0.0, 1.0])  # a zero gradient leaves its rate alone
    assert optimiser.rates(p)[0] == pytest.approx(0.0506)


def _small_net() -> MTRNN:
    cfg = MTRNNConfig(io=2, cf=3, cs=4, tau_io=2, tau_cf=5, tau_cs=16, csc=2)
    return MTRNN(cfg, torch.Generator().manual_seed(0))


def _paper_rule(net: MTRNN, context: nn.Parameter, zeta_gain: float, scale: float = 1.0) -> AdaptiveRates:
    groups = [{"params": list(net.parameters())}, {"params": [context], "scale": scale, "context_of": net}]
    optimiser = make_optimiser(groups, TrainingConfig(optimiser="paper", zeta_gain=zeta_gain))
    assert isinstance(optimiser, AdaptiveRates)
    return optimiser


def test_zeta_is_the_gain_times_the_mean_rate_of_a_csc_units_weights_from_cf_and_cs():
    net = _small_net()
    cfg = net.cfg
    optimiser = _paper_rule(net, nn.Parameter(torch.zeros(5, cfg.csc)), zeta_gain=10.0)
    assert torch.allclose(optimiser.zeta(net, 10.0), torch.full((2,), 0.5))  # before any step: gain * eta^0
    optimiser.state[net.weight]["rate"] = torch.full_like(net.weight, 0.05)
    optimiser.state[net.weight]["rate"][net.csc_slice, cfg.io :] = torch.arange(7.0)  # the Cf u Cs columns
    optimiser.state[net.weight]["rate"][net.csc_slice, : cfg.io] = 100.0  # IO columns: not in eq. (10)
    assert torch.allclose(optimiser.zeta(net, 10.0), torch.full((2,), 30.0))


def test_the_final_states_step_by_psi_times_zeta_times_their_gradient():
    net = _small_net()
    cfg = net.cfg
    c_t = nn.Parameter(torch.zeros(3, cfg.csc))
    optimiser = _paper_rule(net, c_t, zeta_gain=4.0, scale=1e-3)
    optimiser.zero_grad()
    c_t.grad = torch.ones(3, cfg.csc)
    optimiser.step()  # eq. (12): c_T - psi * zeta * dE/dc_T, zeta = 4 * 0.05
    assert torch.allclose(c_t.detach(), torch.full((3, cfg.csc), -1e-3 * 4.0 * 0.05))


def test_sign_based_rprop_and_adam_stay_selectable():
    p = [nn.Parameter(torch.zeros(1))]
    assert isinstance(make_optimiser([{"params": p}], TrainingConfig(optimiser="rprop")), torch.optim.Rprop)
    assert isinstance(make_optimiser([{"params": p}], TrainingConfig(optimiser="adam")), torch.optim.Adam)
    assert isinstance(
        make_optimiser([{"params": p}], TrainingConfig()), torch.optim.Rprop
    )  # the improved modes'
    with pytest.raises(ValueError, match="unknown optimiser"):
        make_optimiser([{"params": p}], TrainingConfig(optimiser="sgd"))
