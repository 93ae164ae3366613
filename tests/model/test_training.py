"""Training (model/training.py): the faithful staged recipe, psi as c_T's step size, modes, seeds."""

from __future__ import annotations

import pytest
import torch
from tiny_corpus import tiny_config, tiny_corpus

from model.config import MTRNNConfig, TrainingConfig
from model.encoding.utterance import PHONEMES, encode_utterance
from model.mtrnn import MTRNN, context_abstraction_loss
from model.training import (
    GENERATION_MARGIN,
    MODES,
    ProgressReporter,
    encode_utterances,
    generation_steps,
    register_mode,
    train,
    train_encoder,
)


def _encoder_and_inputs() -> tuple[MTRNN, torch.Tensor, torch.Tensor]:
    cfg = MTRNNConfig(io=3, cf=5, cs=4, tau_io=2, tau_cf=5, tau_cs=16)
    net = MTRNN(cfg, torch.Generator().manual_seed(0))
    x = torch.rand(6, 9, 3, generator=torch.Generator().manual_seed(1))
    return net, x, torch.tensor([9, 8, 7, 9, 6, 9])


def _initial_targets_and_gradient(psi: float) -> tuple[torch.Tensor, torch.Tensor]:
    """c_T as train_encoder initialises it (same generator), and dE/dc_T at the first epoch."""
    net, x, lengths = _encoder_and_inputs()
    c_t = (
        (torch.rand(6, net.cfg.csc, generator=torch.Generator().manual_seed(7)) * 2 - 1) * 1.0
    ).requires_grad_()
    context_abstraction_loss(net, net.abstract(x, lengths), c_t, psi).backward()
    return c_t.detach(), c_t.grad


def _train_one_epoch(psi: float) -> torch.Tensor:
    net, x, lengths = _encoder_and_inputs()
    report = ProgressReporter(None, 1, [])
    return train_encoder(
        net, x, lengths, psi, TrainingConfig(), torch.Generator().manual_seed(7), report, "s", 1
    )


def test_psi_zero_leaves_the_final_csc_targets_unchanged():
    before, _ = _initial_targets_and_gradient(0.0)
    after = _train_one_epoch(0.0)
    assert torch.equal(after.detach(), before)
    assert not after.requires_grad


@pytest.mark.parametrize("psi", [5e-5, 1e-3])
def test_psi_scales_the_first_rprop_step_of_the_targets(psi):
    """eq. (12): c_T moves by psi * zeta^0 = psi * 0.05 against the sign of its gradient."""
    before, grad = _initial_targets_and_gradient(psi)
    after = _train_one_epoch(psi).detach()
    assert (grad != 0).all()
    expected = before - psi * 0.05 * torch.sign(grad)
    assert torch.allclose(after, expected, rtol=0, atol=1e-7)
    assert torch.allclose((after - before).abs(), torch.full_like(before, psi * 0.05), rtol=1e-2)


def test_weights_take_full_rprop_steps_whatever_psi():
    net, x, lengths = _encoder_and_inputs()
    before = net.weight.detach().clone()
    train_encoder(
        net,
        x,
        lengths,
        1e-4,
        TrainingConfig(),
        torch.Generator().manual_seed(7),
        ProgressReporter(None, 1, []),
        "s",
        1,
    )
    moved = (net.weight.detach() - before).abs()
    connected = net.weight.grad != 0
    assert torch.allclose(moved[connected], torch.full_like(moved[connected], 0.05), atol=1e-6)


def test_generation_length_is_the_longest_training_encoding_plus_margin():
    texts = ["pull the red apple.", "show me the yellow banana."]
    assert generation_steps(texts) == max(len(encode_utterance(t)) for t in texts) + GENERATION_MARGIN
    targets, lengths = encode_utterances(texts, 80)
    assert targets.shape == (2, 80, len(PHONEMES))
    assert lengths.tolist() == [len(encode_utterance(t)) for t in texts]
    # after the utterance the generator is taught silence: the encoding's own uniform activity
    assert torch.allclose(
        targets[0, lengths[0] :], torch.full((80 - lengths[0], len(PHONEMES)), 1 / len(PHONEMES))
    )


def test_faithful_training_reduces_every_stage_loss_and_reports_progress():
    reports = []
    result = train(
        tiny_corpus(variants=1), "faithful", tiny_config(epochs=30), seed=0, progress=reports.append
    )
    for stage in ("auditory", "somatosensory", "visual", "assemblies"):
        losses = [h["loss"] for h in result.history if h["stage"] == stage]
        assert len(losses) == 30 and losses[-1] < losses[0], stage
    assert {r["stage"] for r in reports if "csc" in r} == {"auditory", "somatosensory", "visual"}
    c0 = [r for r in reports if r["stage"] == "auditory"][-1]["csc"]
    assert len(c0) == 12 and len(c0[0]) == result.model.config.auditory.csc
    assert result.csc["auditory_c0"].shape == (12, result.model.config.auditory.csc)
    assert result.meta["mode"] == "faithful" and len(result.meta["ids"]) == 12
    assert result.model.config.generation_steps == result.meta["generation_steps"]


def test_training_is_deterministic_for_a_seed():
    data = tiny_corpus(variants=1)
    a = train(data, "faithful", tiny_config(epochs=3), seed=4)
    b = train(data, "faithful", tiny_config(epochs=3), seed=4)
    c = train(data, "faithful", tiny_config(epochs=3), seed=5)
    sb = b.model.state_dict()
    for name, pa in a.model.state_dict().items():
        assert torch.equal(pa, sb[name]), name
    assert not torch.equal(a.model.auditory.weight, c.model.auditory.weight)


def test_adam_is_selectable():
    config = tiny_config(epochs=5)
    config.training.optimiser = "adam"
    result = train(tiny_corpus(variants=1), "faithful", config, seed=0)
    losses = [h["loss"] for h in result.history if h["stage"] == "auditory"]
    assert losses[-1] < losses[0]


def test_modes_are_a_registry():
    with pytest.raises(ValueError, match="unknown training mode"):
        train(tiny_corpus(variants=1), "no_such_mode", tiny_config(1))
    calls = []

    def fake(data, config, seed, progress):
        calls.append((len(data), config.generation_steps, seed))
        return MODES["faithful"](data, config, seed, progress)

    register_mode("test_fake", fake)
    try:
        train(tiny_corpus(variants=1), "test_fake", tiny_config(1), seed=3)
    finally:
        del MODES["test_fake"]
    assert calls and calls[0][0] == 12 and calls[0][2] == 3 and calls[0][1] > 0


def test_epochs_scale_multiplies_every_stage():
    scaled = TrainingConfig().scaled(0.1)
    assert (scaled.epochs_auditory, scaled.epochs_somatosensory, scaled.epochs_assemblies) == (150, 40, 200)
    assert TrainingConfig().scaled(1e-9).epochs_visual == 1
