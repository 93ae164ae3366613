"""Training (model/training/): the faithful staged recipe, psi as c_T's step size, modes, seeds."""

from __future__ import annotations

import pytest
import torch

from model.assemblies import CellAssemblies
from model.config import MTRNNConfig, TrainingConfig
from model.encoding.utterance import PHONEMES, encode_utterance
from model.mtrnn import MTRNN, context_abstraction_loss
from model.training import MODES, train
from model.training.common import GENERATION_MARGIN, ProgressReporter, encode_utterances, generation_steps
from model.training.faithful import (
    FaithfulOptions,
    assemblies_loss,
    distinct_rows,
    fit_assemblies,
    solve_assemblies,
    train_encoder,
    train_faithful,
    train_faithful_variants,
)
from tests.model.tiny_corpus import tiny_config, tiny_corpus


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
    assert result.meta["config"]["training"]["optimiser"] == "paper"  # eqs. (7)-(10), not sign-based RPROP
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


def test_modes_are_a_registry(monkeypatch: pytest.MonkeyPatch):
    with pytest.raises(ValueError, match="unknown training mode"):
        train(tiny_corpus(variants=1), "no_such_mode", tiny_config(1))
    calls = []

    def fake(data, config, seed, progress):
        trained = MODES["faithful"](data, config, seed, progress)
        calls.append((len(data), trained.model.config.generation_steps, seed))
        return trained

    monkeypatch.setitem(MODES, "test_fake", fake)
    train(tiny_corpus(variants=1), "test_fake", tiny_config(1), seed=3)
    assert calls and calls[0][0] == 12 and calls[0][2] == 3 and calls[0][1] > 0


def test_recordings_of_one_sentence_share_one_auditory_context():
    """3.3: c_a,0 is trained per sentence, so a scene's recordings get the same c_a,0 (and the
    progress reports still show one row per recording)."""
    data = tiny_corpus(variants=2)
    reports = []
    result = train(data, "faithful", tiny_config(epochs=3), seed=0, progress=reports.append)
    c0 = result.csc["auditory_c0"]
    assert c0.shape == (24, result.model.config.auditory.csc)
    for i in range(0, 24, 2):  # tiny_corpus lists a scene's variants next to each other
        assert data.utterances[i] == data.utterances[i + 1]
        assert (c0[i] == c0[i + 1]).all()
    assert len(set(map(tuple, c0.tolist()))) == 12
    last = [r for r in reports if r["stage"] == "auditory"][-1]["csc"]
    assert torch.allclose(torch.tensor(last), torch.as_tensor(c0))


def test_distinct_rows_maps_each_recording_to_its_sentence():
    sentences, rows = distinct_rows(["a.", "b.", "a.", "c.", "b."])
    assert sentences == ["a.", "b.", "c."] and rows.tolist() == [0, 1, 0, 2, 1]


def test_scene_targets_are_shared_by_the_recordings_of_a_scene():
    net, x, lengths = _encoder_and_inputs()
    groups = torch.tensor([0, 0, 1, 1, 2, 2])
    reports = []
    table = train_encoder(
        net,
        x,
        lengths,
        1e-3,
        TrainingConfig(),
        torch.Generator().manual_seed(7),
        ProgressReporter(reports.append, 1, []),
        "s",
        2,
        groups,
    )
    assert table.shape == (3, net.cfg.csc)
    shown = torch.tensor(reports[-1]["csc"])
    assert shown.shape == (6, net.cfg.csc) and torch.equal(shown[0], shown[1])


def test_faithful_options_default_to_the_paper_and_are_recorded():
    data = tiny_corpus(variants=2)
    default = train(data, "faithful", tiny_config(epochs=2), seed=0)
    assert default.meta["faithful"] == {"perception_targets": "recording", "assemblies_solver": "lms"}
    assert len({tuple(r) for r in default.csc["somatosensory_cT"].tolist()}) == 24
    options = FaithfulOptions(perception_targets="scene", assemblies_solver="optimum")
    config = tiny_config(epochs=2)
    config.generation_steps = default.model.config.generation_steps
    shared = train_faithful(data, config, 0, None, options)
    assert shared.meta["faithful"] == {"perception_targets": "scene", "assemblies_solver": "optimum"}
    assert len({tuple(r) for r in shared.csc["somatosensory_cT"].tolist()}) == 12
    with pytest.raises(ValueError, match="perception_targets"):
        train_faithful(data, config, 0, None, FaithfulOptions(perception_targets="nope"))


def test_variants_sharing_mtrnn_a_train_as_each_would_alone():
    data = tiny_corpus(variants=2)
    configs = []
    for psi_s, encoder_epochs in ((0.0, 3), (5e-2, 3), (5e-2, 4)):
        config = tiny_config(epochs=3)
        config.training.psi_s, config.training.epochs_somatosensory = psi_s, encoder_epochs
        configs.append(config)
    variants = train_faithful_variants(data, configs, seed=4)
    assert len(variants) == 3
    for config, variant in zip(configs, variants, strict=True):
        alone = train_faithful(data, config, 4)
        for name in ("auditory_c0", "somatosensory_cT", "visual_cT"):
            assert torch.equal(torch.as_tensor(variant.csc[name]), torch.as_tensor(alone.csc[name]))
        for a, b in zip(variant.model.state_dict().values(), alone.model.state_dict().values(), strict=True):
            assert torch.equal(a, b)
    targets = [torch.as_tensor(v.csc["somatosensory_cT"]) for v in variants]
    assert not torch.equal(targets[0], targets[1])  # psi_s moved the second's targets
    other = tiny_config(epochs=3)
    other.training.alpha = 0.5  # MTRNN_a's teacher forcing: another stage 1
    with pytest.raises(ValueError, match="may differ only"):
        train_faithful_variants(data, [configs[0], other], seed=4)


def test_mode_options_are_selectable_through_the_config():
    data = tiny_corpus(variants=2)
    config = tiny_config(epochs=2)
    config.options = {"assemblies_solver": "optimum"}
    trained = train(data, "faithful", config, seed=0)
    assert trained.meta["faithful"]["assemblies_solver"] == "optimum"
    assert trained.model.config.options == {"assemblies_solver": "optimum"}
    config.options = {"solver": "optimum"}
    with pytest.raises(ValueError, match=r"unknown FaithfulOptions option\(s\) \['solver'\]"):
        train(data, "faithful", config, seed=0)


def test_optimum_assemblies_recover_a_linear_association_exactly():
    g = torch.Generator().manual_seed(0)
    c_s, c_v = torch.randn(40, 3, generator=g), torch.randn(40, 2, generator=g)
    truth = CellAssemblies(3, 2, 4, weight_init=2.0, seed=1)
    with torch.no_grad():
        c_a0 = truth(c_s, c_v)
    fitted = CellAssemblies(3, 2, 4, seed=2)
    loss = solve_assemblies(fitted, c_s, c_v, c_a0)
    assert loss < 1e-10 and assemblies_loss(fitted, c_s, c_v, c_a0).item() < 1e-10
    assert torch.allclose(fitted.weight, truth.weight, atol=1e-4)


def test_optimum_assemblies_reach_a_lower_lms_error_than_rprop_epochs():
    """eq. (16) solved to convergence is at most the error a fixed RPROP budget reaches."""
    g = torch.Generator().manual_seed(3)
    c_s, c_v, c_a0 = (
        torch.randn(30, 3, generator=g),
        torch.randn(30, 2, generator=g),
        3 * torch.randn(30, 4, generator=g),
    )
    descended = CellAssemblies(3, 2, 4, seed=2)
    fit_assemblies(descended, c_s, c_v, c_a0, TrainingConfig(), ProgressReporter(None, 1, []), 200)
    solved = CellAssemblies(3, 2, 4, seed=2)
    assert solve_assemblies(solved, c_s, c_v, c_a0) < assemblies_loss(descended, c_s, c_v, c_a0).item()
