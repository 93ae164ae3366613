"""MTRNN (eqs. 2-5, 11-12): the update rule, connectivity, activation, losses and gradients."""

from __future__ import annotations

import math

import pytest
import torch
from torch import nn

from model.config import KAPPA_H, KAPPA_W, MTRNNConfig
from model.mtrnn import (
    MTRNN,
    connectivity_mask,
    context_abstraction_loss,
    kl_divergence,
    scaled_logistic,
    scaled_logistic_inverse,
)


def f(z: float) -> float:
    """The scaled logistic written out by hand."""
    return (1 + 2 * KAPPA_H) / (1 + math.exp(-KAPPA_W * z)) - KAPPA_H


def three_unit_net() -> MTRNN:
    """One IO, one Cf, one Cs (= Csc) unit; logistic IO; every allowed weight set by hand."""
    cfg = MTRNNConfig(io=1, cf=1, cs=1, csc=1, tau_io=2, tau_cf=4, tau_cs=10)
    net = MTRNN(cfg)
    with torch.no_grad():
        net.weight.copy_(torch.tensor([[0.5, -1.0, 9.0], [2.0, 0.3, -0.7], [9.0, 1.5, 0.2]]))
        net.bias.copy_(torch.tensor([0.1, -0.2, 0.05]))
    return net


def test_eq3_matches_a_hand_computed_three_unit_step():
    net = three_unit_net()
    c0 = 0.8
    # t = 0: z_0 = (0, 0, c_0) (eq. 3, Csc holds c_0); y_0 = f(z_0).
    y0 = [f(0.0), f(0.0), f(c0)]
    # t = 1, eq. (2)/(5) without teacher: x_1 = y_0. IO<->Cs weights (the 9.0s) are masked out.
    x1 = y0
    z1_io = (1 - 1 / 2) * 0.0 + (1 / 2) * (0.5 * x1[0] - 1.0 * x1[1] + 0.1)
    z1_cf = (1 - 1 / 4) * 0.0 + (1 / 4) * (2.0 * x1[0] + 0.3 * x1[1] - 0.7 * x1[2] - 0.2)
    z1_cs = (1 - 1 / 10) * c0 + (1 / 10) * (1.5 * x1[1] + 0.2 * x1[2] + 0.05)
    _, states = net.generate(torch.tensor([[c0]]), steps=2, return_states=True)
    assert states[0, 0].tolist() == pytest.approx([0.0, 0.0, c0], abs=1e-7)
    assert states[0, 1].tolist() == pytest.approx([z1_io, z1_cf, z1_cs], abs=1e-6)


def test_abstraction_feeds_the_sensory_input_to_io():
    net = three_unit_net()
    x = torch.tensor([[[0.7], [0.2]]])  # [B=1, T=2, io=1]
    _, states = net.abstract(x, return_states=True)
    y0 = [f(0.0)] * 3  # every unit starts at z = 0
    z1_io = 0.5 * (0.5 * 0.7 - 1.0 * y0[1] + 0.1)  # eq. (2): the IO input is x*_t, not y_{t-1}
    z1_cs = 0.1 * (1.5 * y0[1] + 0.2 * y0[2] + 0.05)
    assert states[0, 0, 0].item() == pytest.approx(z1_io, abs=1e-6)
    assert states[0, 0, 2].item() == pytest.approx(z1_cs, abs=1e-6)


def test_io_and_cs_are_never_connected():
    cfg = MTRNNConfig(io=3, cf=4, cs=5, tau_io=2, tau_cf=5, tau_cs=30)
    mask = connectivity_mask(cfg)
    io, cs = slice(0, 3), slice(7, 12)
    assert mask[io, cs].sum() == 0 and mask[cs, io].sum() == 0
    assert mask[io, io].all() and mask[3:7, :].all() and mask[cs, 3:12].all()

    net = MTRNN(cfg, torch.Generator().manual_seed(0))
    c_t = net.abstract(torch.rand(2, 6, 3, generator=torch.Generator().manual_seed(1)))
    c_t.sum().backward()
    assert net.weight.grad[io, cs].abs().sum() == 0 and net.weight.grad[cs, io].abs().sum() == 0
    assert net.weight.grad[cs, 3:7].abs().sum() > 0
    with torch.no_grad():  # whatever sits in the masked blocks changes nothing
        net.weight[io, cs] = 100.0
        net.weight[cs, io] = -100.0
    assert torch.equal(net.abstract(torch.rand(2, 6, 3, generator=torch.Generator().manual_seed(1))), c_t)


def test_csc_is_the_first_half_of_cs_rounded_up():
    cfg = MTRNNConfig(io=44, cf=80, cs=23, tau_io=2, tau_cf=5, tau_cs=70)
    assert cfg.csc == 12
    assert MTRNN(cfg).csc_slice == slice(124, 136)


def test_scaled_logistic_range_slope_and_inverse():
    z = torch.tensor([-50.0, 0.0, 50.0])
    assert scaled_logistic(z).tolist() == pytest.approx([-KAPPA_H, 0.5, 1 + KAPPA_H], abs=1e-5)
    slope = torch.func.grad(lambda x: scaled_logistic(x))(torch.tensor(0.0))
    assert slope.item() == pytest.approx((1 + 2 * KAPPA_H) * KAPPA_W / 4)
    y = torch.linspace(-0.3, 1.3, 9)
    assert scaled_logistic(scaled_logistic_inverse(y)).tolist() == pytest.approx(y.tolist(), abs=1e-5)


def test_softmax_only_on_the_generators_io():
    cfg = MTRNNConfig(io=4, cf=3, cs=2, tau_io=2, tau_cf=5, tau_cs=70, io_activation="softmax")
    y = MTRNN(cfg).activation(torch.randn(3, 9))
    assert y[:, :4].sum(dim=1).tolist() == pytest.approx([1.0] * 3)
    assert (y[:, 4:] > -KAPPA_H).all() and (y[:, 4:] < 1 + KAPPA_H).all()


def test_teacher_forcing_mixes_alpha_of_the_desired_output():
    cfg = MTRNNConfig(io=4, cf=3, cs=2, tau_io=2, tau_cf=5, tau_cs=70, io_activation="softmax")
    net = MTRNN(cfg, torch.Generator().manual_seed(0))
    c0 = torch.zeros(1, 1)
    teacher = torch.softmax(torch.randn(1, 5, 4, generator=torch.Generator().manual_seed(2)), dim=-1)
    free = net.generate(c0, 5)
    assert torch.equal(net.generate(c0, 5, teacher=teacher, alpha=0.0), free)
    forced = net.generate(c0, 5, teacher=teacher, alpha=0.1)
    assert torch.equal(forced[:, :1], free[:, :1])  # y*_{t-1} enters the input from t = 1 on
    assert not torch.allclose(forced[:, 1:], free[:, 1:])


def test_kl_divergence_is_zero_for_the_target_and_positive_otherwise():
    t = torch.softmax(torch.randn(2, 6, 5), dim=-1)
    assert kl_divergence(t, t).item() == pytest.approx(0.0, abs=1e-5)
    assert kl_divergence(t, torch.full_like(t, 0.2)).item() > 0


def test_self_organisation_forcing_splits_the_error_between_weights_and_targets():
    """eq. (11): the final Csc state gets (1 - psi) of the LMS error; eq. (12): c_T the error."""
    cfg = MTRNNConfig(io=2, cf=3, cs=4, tau_io=2, tau_cf=5, tau_cs=30)
    net = MTRNN(cfg, torch.Generator().manual_seed(0))
    z_t = torch.randn(3, 2, requires_grad=True)
    c_t = torch.randn(3, 2, requires_grad=True)
    psi = 0.25
    context_abstraction_loss(net, z_t, c_t, psi).backward()
    b = net.csc_bias.detach()
    err = scaled_logistic(z_t.detach()) - scaled_logistic(c_t.detach() + b)
    fprime = torch.func.vmap(torch.func.vmap(torch.func.grad(scaled_logistic)))
    expected_z = (1 - psi) * err * fprime(z_t.detach()) / 3  # mean over the 3 sequences
    expected_c = -err * fprime(c_t.detach() + b) / 3
    assert torch.allclose(z_t.grad, expected_z, atol=1e-6)
    assert torch.allclose(c_t.grad, expected_c, atol=1e-6)
    assert net.weight.grad is None  # the loss on given states reaches no weight directly


class _Call(nn.Module):
    """Lets `torch.func.functional_call` run one MTRNN method with given weights and biases."""

    def __init__(self, net: MTRNN, method: str) -> None:
        super().__init__()
        self.net, self.method = net, method

    def forward(self, *args):
        return getattr(self.net, self.method)(*args)


def test_float64_gradients_match_finite_differences():
    cfg = MTRNNConfig(io=3, cf=2, cs=2, csc=1, tau_io=2, tau_cf=4, tau_cs=8, io_activation="softmax")
    net = MTRNN(cfg, torch.Generator().manual_seed(0)).double()
    g = torch.Generator().manual_seed(3)
    target = torch.softmax(torch.randn(2, 5, 3, generator=g, dtype=torch.float64), dim=-1)
    x = torch.rand(2, 6, 3, generator=g, dtype=torch.float64)
    lengths = torch.tensor([6, 4])
    c0 = torch.randn(2, 1, generator=g, dtype=torch.float64, requires_grad=True)
    w = net.weight.detach().clone().requires_grad_(True)
    b = net.bias.detach().clone().requires_grad_(True)
    generate, abstract = _Call(net, "generate"), _Call(net, "abstract")

    def generation_loss(weight, bias, c0):  # MTRNN_a: KLD with teacher forcing (eqs. 5-9)
        out = torch.func.functional_call(
            generate, {"net.weight": weight, "net.bias": bias}, (c0, 5, target, 0.1)
        )
        return kl_divergence(target, out)

    def abstraction(weight, bias):  # MTRNN_s/v: the final Csc states (eq. 11 starts from them)
        return torch.func.functional_call(abstract, {"net.weight": weight, "net.bias": bias}, (x, lengths))

    assert torch.autograd.gradcheck(generation_loss, (w, b, c0))
    assert torch.autograd.gradcheck(abstraction, (w, b))
