"""Issue 16's options of `end_to_end` (model/training/end_to_end/factors.py): the slots the colour
and shape features tell, recoloured recordings, and the factorised visual pathway, which must
checkpoint and describe like any other model."""

from __future__ import annotations

import numpy as np
import torch

from model import checkpoint
from model.assemblies import WordAssemblies
from model.config import MTRNNConfig
from model.mtrnn import MTRNN
from model.training.common import prepare
from model.training.end_to_end import EndToEndOptions, WordSlots, train_end_to_end
from model.training.end_to_end.factors import (
    COLOUR_COLUMNS,
    SHAPE_COLUMNS,
    colour_and_shape_slots,
    csc_pathways,
    factorise,
    recoloured,
)
from tests.model.tiny_corpus import tiny_config, tiny_corpus


def test_the_slots_of_colour_and_shape_are_read_off_the_recordings() -> None:
    data = tiny_corpus(variants=2)  # vision: colour in column 16 + c, the shape in the distances
    slots = WordSlots.from_utterances(data.utterances)
    heard = slots.one_hot(data.utterances)
    assert colour_and_shape_slots(heard, slots.sizes, data.vision) == (1, 2)
    swapped = [v[:, [*range(16, 19), *range(3, 16), 0, 1, 2, 19, 20]] for v in data.vision]
    assert colour_and_shape_slots(heard, slots.sizes, swapped)[0] == 2  # the columns decide


def test_recolouring_swaps_the_colour_columns_and_the_colour_word_only() -> None:
    steps, lengths = 9, torch.tensor([9, 5, 7, 3])
    vision = torch.rand(4, steps, 21)
    vision[torch.arange(steps)[None, :] >= lengths[:, None]] = 0.0
    colours = [0, 0, 1, 2]  # recordings 0 and 1 share a colour: never each other's donor
    heard = torch.zeros(4, 6)
    heard[torch.arange(4), 0] = 1.0  # slot 0 (one phrase), slot 1 colour (3), slot 2 shape (2)
    heard[torch.arange(4), [1 + c for c in colours]] = 1.0
    heard[torch.arange(4), [4, 5, 4, 5]] = 1.0
    out, words = recoloured(vision, lengths, heard, [1, 3, 2], 1, torch.Generator().manual_seed(3))
    keep = [c for c in range(21) if c not in COLOUR_COLUMNS]
    torch.testing.assert_close(out[..., keep], vision[..., keep])
    torch.testing.assert_close(words[:, [0, 4, 5]], heard[:, [0, 4, 5]])  # action and shape stay
    colour = list(COLOUR_COLUMNS)
    for i in range(4):
        donor = next(
            j
            for j in range(4)
            if torch.equal(words[i, 1:4], heard[j, 1:4])
            and torch.allclose(out[i, 0, colour], vision[j, 0, colour])
        )
        assert colours[donor] != colours[i]
        n, m = int(lengths[i]), int(lengths[donor])
        resampled = np.stack(
            [np.interp(np.linspace(0, m - 1, n), np.arange(m), vision[donor, :m, c].numpy()) for c in colour],
            1,
        )
        np.testing.assert_allclose(out[i, :n, colour].numpy(), resampled, atol=1e-6)  # the whole track
        torch.testing.assert_close(out[i, n:], vision[i, n:])  # padding untouched


def _factorised_pair() -> tuple[MTRNN, WordAssemblies]:
    cfg = MTRNNConfig(io=21, cf=8, cs=8, tau_io=2, tau_cf=5, tau_cs=16)
    net = MTRNN(cfg, torch.Generator().manual_seed(0))
    factorise(net)
    colour_units, shape_units = csc_pathways(cfg)
    assemblies = WordAssemblies(
        3,
        cfg.csc,
        4,
        [["pull", "push"], ["blue", "red"], ["apple", "dice"]],
        visual_readout=[None, colour_units, shape_units],
    )
    return net, assemblies


def test_factorised_colour_words_get_no_gradient_from_shape_features() -> None:
    net, assemblies = _factorised_pair()
    vision = torch.rand(2, 10, 21, requires_grad=True)
    z_v = assemblies.visual_logits(net.abstract(vision))
    (colour_grad,) = torch.autograd.grad(z_v[:, 2:4].sum(), vision, retain_graph=True)
    (shape_grad,) = torch.autograd.grad(z_v[:, 4:6].sum(), vision, retain_graph=True)
    (action_grad,) = torch.autograd.grad(z_v[:, 0:2].sum(), vision, retain_graph=True)
    others = [c for c in range(21) if c not in COLOUR_COLUMNS]
    colour_grad, shape_grad, action_grad = (g[:, :-2] for g in (colour_grad, shape_grad, action_grad))
    # (the last two steps cannot reach the Csc yet: IO -> Cf -> Cs)
    assert colour_grad[..., others].abs().max() == 0.0
    assert colour_grad[..., list(COLOUR_COLUMNS)].abs().min() > 0.0
    assert shape_grad[..., list(COLOUR_COLUMNS)].abs().max() == 0.0
    assert shape_grad[..., list(SHAPE_COLUMNS)].abs().min() > 0.0
    assert action_grad.abs().min() > 0.0  # the action's units read both pathways
    z_v.sum().backward()
    assert assemblies.weight_v.grad[2:4, csc_pathways(net.cfg)[1]].abs().max() == 0.0
    assert net.weight.grad[net.mask == 0].abs().max() == 0.0


def test_plain_word_assemblies_keep_their_kwargs_and_read_all_of_c_v() -> None:
    plain = WordAssemblies(3, 4, 5, [["a", "b"], ["c", "d"]], seed=2)
    assert "visual_readout" not in plain.init_kwargs()  # earlier checkpoints rebuild unchanged
    assert "readout_v" not in plain.state_dict()
    c_v = torch.rand(2, 4)
    expected = torch.sigmoid(0.92 * c_v) * (1 + 2 * 0.35795) - 0.35795
    torch.testing.assert_close(plain.visual_logits(c_v), expected @ plain.weight_v.T + plain.bias_v)


def test_composing_options_train_checkpoint_and_describe_the_same(tmp_path) -> None:
    data = tiny_corpus(variants=2)
    config = prepare(data, tiny_config())
    options = EndToEndOptions(
        auditory_epochs=4,
        auditory_attempts=1,
        perception_epochs=3,
        average_from=0.0,
        recombine_objects=1.0,
        factorised_vision=True,
    )
    trained = train_end_to_end(data, config, seed=1, options=options)
    assert trained.meta["factors"] == {"colour_slot": 1, "shape_slot": 2}
    model = trained.model
    assert model.visual.weight[model.visual.mask == 0].abs().max() == 0.0  # still after folding
    readout = model.assemblies.init_kwargs()["visual_readout"]
    assert readout[0] is None and readout[1:] == list(csc_pathways(model.config.visual))
    before = model.describe_batch(data.proprioception[:4], data.vision[:4], trained.lexicon)
    checkpoint.save(model, tmp_path / "m", trained.meta)
    loaded, _ = checkpoint.load(tmp_path / "m")
    torch.testing.assert_close(loaded.visual.mask, model.visual.mask)
    after = loaded.describe_batch(data.proprioception[:4], data.vision[:4], trained.lexicon)
    for b, a in zip(before, after, strict=True):
        assert b.text == a.text
        np.testing.assert_array_equal(b.activity, a.activity)
    timeline = loaded.timeline(data.proprioception[0], data.vision[0], trained.lexicon)
    assert timeline.texts[-1] == before[0].text
