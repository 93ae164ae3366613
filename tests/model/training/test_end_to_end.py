"""The `end_to_end` training mode: word slots, word-unit cell assemblies, folded input
normalisation, held-out calibration and a whole (tiny) training that checkpoints faithfully."""

from __future__ import annotations

from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from data.scenario import all_scenes
from model import checkpoint
from model.assemblies import ASSEMBLIES, WordAssemblies
from model.config import MTRNNConfig
from model.data import SequenceSet
from model.encoding.utterance import Lexicon
from model.multimtrnn import Description, MultiMTRNN
from model.training import MODES
from model.training.common import TrainedModel, encode_utterances, prepare
from model.training.end_to_end import (
    EndToEndOptions,
    InputNormaliser,
    PerceptionBatch,
    WordSlots,
    calibrate,
    combinations_said,
    reading_points,
    recombination_loss,
    selection_split,
    train_end_to_end,
)
from tests.model.tiny_corpus import tiny_config, tiny_corpus

GRAMMAR = [s.utterance for s in all_scenes()]


def test_word_slots_are_read_off_the_heard_utterances() -> None:
    slots = WordSlots.from_utterances(GRAMMAR)
    assert slots.slots == (
        ("pull", "push", "show me", "slide"),  # "show" and "me" are always heard together
        ("blue", "green", "red", "yellow"),  # "the" is heard every time: no slot
        ("apple", "banana", "dice", "phone"),
    )
    assert slots.indices("show me the red apple.") == [2, 2, 0]
    p = slots.one_hot(["slide the yellow phone.", "pull the blue apple."])
    assert p.tolist() == [
        [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1],
        [1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0],
    ]


def test_word_slots_reject_sentences_of_different_structure() -> None:
    with pytest.raises(ValueError, match="informative phrases"):
        WordSlots.from_utterances(["pull the red apple.", "push the apple.", "slide the blue dice."])


def test_reading_points_span_from_start_fraction_to_last_step() -> None:
    steps = reading_points(torch.tensor([10, 20]), points=3, start=0.3)
    assert steps.tolist() == [[2, 6, 9], [5, 12, 19]]
    assert reading_points(torch.tensor([7]), points=1, start=0.3).tolist() == [[6]]


def test_folded_normalisation_reads_raw_inputs_exactly_as_trained() -> None:
    torch.manual_seed(0)
    cfg = MTRNNConfig(io=5, cf=6, cs=4, tau_io=2, tau_cf=5, tau_cs=50)
    net = MTRNN_with_seed(cfg, 1)
    x = torch.rand(3, 9, 5) * 0.2 + 0.4
    lengths = torch.tensor([9, 7, 5])
    normaliser = InputNormaliser.fit(x, lengths)
    trained_view = net.abstract(normaliser(x), lengths)
    normaliser.fold_into(net)
    assert torch.allclose(net.abstract(x, lengths), trained_view, atol=1e-5)


def MTRNN_with_seed(cfg: MTRNNConfig, seed: int):  # noqa: N802 - reads like the class it builds
    from model.mtrnn import MTRNN

    return MTRNN(cfg, torch.Generator().manual_seed(seed))


def test_word_assemblies_pick_one_word_per_slot_and_rebuild_from_kwargs() -> None:
    slots = WordSlots.from_utterances(GRAMMAR)
    cas = WordAssemblies(12, 12, 12, [list(s) for s in slots.slots], seed=3)
    c_s, c_v = torch.randn(5, 12), torch.randn(5, 12)
    p = cas.word_activity(cas.word_logits(c_s, c_v), hard=True)
    assert p.shape == (5, 12)
    assert all(torch.equal(part.sum(dim=1), torch.ones(5)) for part in p.split([4, 4, 4], dim=1))
    assert torch.allclose(cas(c_s, c_v), cas.speak(p))  # c_a,0 = E p + e with the winners
    rebuilt = ASSEMBLIES[cas.kind](**cas.init_kwargs())
    rebuilt.load_state_dict(cas.state_dict())
    assert torch.equal(rebuilt(c_s, c_v), cas(c_s, c_v))
    assert cas.words[6] == "red"


def test_logistic_word_units_threshold_at_one_half() -> None:
    cas = WordAssemblies(2, 2, 3, [["a", "b"], ["c"]], slot_softmax=False)
    z = torch.tensor([[2.0, -1.0, 0.5]])
    assert cas.word_activity(z, hard=True).tolist() == [[1.0, 0.0, 1.0]]


def test_calibration_trusts_the_informative_encoder_only() -> None:
    rng = torch.Generator().manual_seed(0)
    cas = WordAssemblies(2, 2, 3, [["a", "b", "c"]])
    heard = torch.nn.functional.one_hot(torch.arange(60) % 3, 3).float()
    z_informative = 4.0 * heard + 0.5 * torch.randn(60, 3, generator=rng)
    z_confident_noise = (
        6.0 * torch.nn.functional.one_hot(torch.randint(0, 3, (60,), generator=rng), 3).float()
    )
    g_s, g_v, accuracy = calibrate(cas, z_informative, z_confident_noise, heard)
    assert accuracy == 1.0
    assert g_s[0] > 0.5
    assert g_v[0] < 0.1 * g_s[0]


def _two_slot_recordings(n: int = 40) -> tuple[WordAssemblies, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Slot 0 is told by z_s only, slot 1 by z_v only (each encoder sure of its own slot)."""
    rng = torch.Generator().manual_seed(0)
    cas = WordAssemblies(2, 2, 3, [["a", "b"], ["c", "d"]])
    first, second = torch.randint(0, 2, (n,), generator=rng), torch.randint(0, 2, (n,), generator=rng)
    heard = torch.cat([F.one_hot(first, 2), F.one_hot(second, 2)], dim=1).float()
    z_s = torch.cat([8.0 * F.one_hot(first, 2) - 4.0, torch.zeros(n, 2)], dim=1)[:, None, :]
    z_v = torch.cat([torch.zeros(n, 2), 8.0 * F.one_hot(second, 2) - 4.0], dim=1)[:, None, :]
    return cas, z_s, z_v, heard


def test_recombination_learns_which_sense_tells_each_slot() -> None:
    cas, z_s, z_v, heard = _two_slot_recordings()
    mix = torch.zeros(2, requires_grad=True)
    loss = recombination_loss(cas, z_s, z_v, heard, mix, torch.Generator().manual_seed(1), pairs=3)
    loss.backward()
    # slot 0's word comes with recording A (MTRNN_s), slot 1's with recording B (MTRNN_v)
    assert mix.grad[0] < 0 < mix.grad[1]
    right = torch.tensor([20.0, -20.0])
    wrong = -right
    g = torch.Generator
    assert recombination_loss(cas, z_s, z_v, heard, right, g().manual_seed(1), 3) < 0.05
    assert recombination_loss(cas, z_s, z_v, heard, wrong, g().manual_seed(1), 3) > 1.0


def test_recombination_penalises_an_encoder_that_memorised_the_other_sense() -> None:
    cas, z_s, z_v, heard = _two_slot_recordings()
    mix = torch.tensor([20.0, -20.0])
    honest = recombination_loss(cas, z_s, z_v, heard, mix, torch.Generator().manual_seed(2), 1)
    memorised = z_s.clone()
    memorised[..., 2:] = 8.0 * heard[:, None, 2:] - 4.0  # MTRNN_s also "knows" slot 1 of its own recording
    worse = recombination_loss(cas, memorised, z_v, heard, mix, torch.Generator().manual_seed(2), 1)
    assert honest < 0.01 and worse > 0.1  # ties on every pair whose two recordings differ in slot 1


def test_selection_holds_out_whole_scenes_and_keeps_every_word() -> None:
    data = tiny_corpus(variants=2)
    slots = WordSlots.from_utterances(data.utterances)
    fit, held = selection_split(data, slots, scenes=3, seed=0)
    assert sorted(fit + held) == list(range(len(data)))
    held_scenes = {data.ids[i].rsplit("-", 1)[0] for i in held}
    fit_scenes = {data.ids[i].rsplit("-", 1)[0] for i in fit}
    assert 0 < len(held_scenes) <= 3 and not held_scenes & fit_scenes
    fit_words = [slots.indices(data.utterances[i]) for i in fit]
    for k, slot in enumerate(slots.slots):
        assert {w[k] for w in fit_words} == set(range(len(slot)))


def _tiny_options() -> EndToEndOptions:
    return EndToEndOptions(
        auditory_epochs=4,
        auditory_attempts=2,
        perception_epochs=4,
        select_every=2,
        selection_scenes=2,
        average_from=0.0,
    )


def test_training_records_options_and_describes_through_the_model_path(tmp_path) -> None:
    data = tiny_corpus(variants=2)
    config = prepare(data, tiny_config())
    trained = train_end_to_end(data, config, seed=1, options=_tiny_options())
    assert trained.meta["mode"] == "end_to_end"
    assert trained.meta["end_to_end"] == asdict(_tiny_options())
    generator = trained.meta["generator"]  # 4 epochs say little: a restart
    assert 1 <= len(generator["combinations_said"]) == len(generator["epochs"]) <= 2
    assert trained.meta["selection"]["epoch"] in (2, 4)
    assert trained.model.config.visual.io == 21  # the centroid option
    assert {h["stage"] for h in trained.history} == {"auditory", "perception"}
    lexicon = trained.lexicon
    before = trained.model.describe_batch(data.proprioception[:3], data.vision[:3], lexicon)
    checkpoint.save(trained.model, tmp_path / "m", trained.meta)
    model, meta = checkpoint.load(tmp_path / "m")
    after = model.describe_batch(data.proprioception[:3], data.vision[:3], lexicon)
    assert meta["end_to_end"] == trained.meta["end_to_end"]
    for b, a in zip(before, after, strict=True):
        assert b.text == a.text
        np.testing.assert_array_equal(b.activity, a.activity)


class _SpeakingModel:
    """Stands in for MTRNN_a behind E p + e: says the sentence of each word combination p, except
    that it calls every "green" thing a "phone" (a phrase it never learned to compose)."""

    def __init__(self, slots: WordSlots, steps: int) -> None:
        self.slots, self.steps = slots, steps

    def generate(self, p: torch.Tensor) -> torch.Tensor:
        sentences = []
        for row in p:
            action, colour, shape = (
                slot[int(part.argmax())]
                for slot, part in zip(self.slots.slots, row.split(self.slots.sizes), strict=True)
            )
            shape = "phone" if colour == "green" else shape
            sentences.append(f"{action} the {colour} {shape}.")
        return encode_utterances(sentences, self.steps)[0]


def test_the_learner_hears_which_word_combinations_its_generator_says() -> None:
    slots = WordSlots.from_utterances(GRAMMAR)
    cas = WordAssemblies(2, 2, sum(slots.sizes), [list(s) for s in slots.slots])
    with torch.no_grad():  # E = identity, e = 0: c_a,0 is p itself
        cas.projection.copy_(torch.eye(sum(slots.sizes)))
        cas.projection_bias.zero_()
    said = combinations_said(_SpeakingModel(slots, 60), cas, slots, Lexicon.from_sentences(GRAMMAR))
    assert said == 52 / 64  # green apple, banana and dice come out as phones: 4 actions x 3 shapes wrong


def test_time_warp_replays_each_recording_at_its_own_speed() -> None:
    ramp = torch.arange(10.0).reshape(1, 10, 1).repeat(3, 1, 2)
    lengths = torch.tensor([10, 6, 3])
    seen = PerceptionBatch(ramp, lengths, ramp.clone(), lengths.clone(), torch.zeros(3, 4))
    warped = seen.time_warped(0.5, torch.Generator().manual_seed(1))
    assert torch.equal(warped.proprioception_lengths, warped.vision_lengths)
    for x, n, old in zip(warped.proprioception, warped.proprioception_lengths, lengths, strict=True):
        assert 0.5 * old - 1 <= n <= 2 * old + 1
        steps = x[:n, 0]  # a ramp stays a ramp from the first to the last original step
        assert steps[0] == 0 and torch.isclose(steps[-1], old - 1.0)
        assert torch.allclose(steps.diff(), steps.diff()[0].expand(n - 1), atol=1e-5)
        assert (x[n:] == 0).all()
    assert not torch.equal(warped.proprioception_lengths, lengths)


def test_mode_is_registered_and_deterministic() -> None:
    assert "end_to_end" in MODES
    assert MODES["end_to_end"] is train_end_to_end
    data = tiny_corpus(variants=1)
    augmented = EndToEndOptions(auditory_epochs=2, perception_epochs=2, input_noise=0.1, vision_window=5)
    options = replace(
        augmented, time_warp=0.3, recombine=1.0, selection_scenes=0, average_from=0.5, weight_decay=1e-4
    )
    a = train_end_to_end(data, prepare(data, tiny_config()), seed=5, options=options)
    b = train_end_to_end(data, prepare(data, tiny_config()), seed=5, options=options)
    for (name, x), (_, y) in zip(a.model.state_dict().items(), b.model.state_dict().items(), strict=True):
        assert torch.equal(x, y), name


def test_weight_averaging_is_the_final_state_and_excludes_selection(tmp_path) -> None:
    data = tiny_corpus(variants=2)
    options = EndToEndOptions(auditory_epochs=1, perception_epochs=4, average_from=0.0)
    last = train_end_to_end(data, prepare(data, tiny_config()), seed=2, options=options).model
    trained = train_end_to_end(
        data, prepare(data, tiny_config()), seed=2, options=replace(options, average_from=0.5)
    )
    averaged = trained.model
    assert not torch.equal(last.visual.weight, averaged.visual.weight)
    assert trained.meta["selection"]["sense_of_slot_is_s"]  # the learned sense of each slot
    checkpoint.save(averaged, tmp_path / "m", trained.meta)  # nothing but the model's tensors
    reloaded, _ = checkpoint.load(tmp_path / "m")
    for (name, x), (_, y) in zip(averaged.state_dict().items(), reloaded.state_dict().items(), strict=True):
        assert torch.equal(x, y), name
    with pytest.raises(ValueError, match="selection_scenes"):
        replace(options, average_from=0.5, selection_scenes=2)


def test_plain_end_to_end_trains_everything_through_the_auditory_loss() -> None:
    data = tiny_corpus(variants=1)
    config = prepare(data, tiny_config())
    options = EndToEndOptions(word_loss=False, joint_epochs=3, hard_words=False)
    model = train_end_to_end(data, config, seed=0, options=options).model
    initial = train_end_to_end(
        data, prepare(data, tiny_config()), seed=0, options=EndToEndOptions(word_loss=False, joint_epochs=0)
    ).model
    for net in ("somatosensory", "visual", "auditory"):
        assert not torch.equal(getattr(model, net).weight, getattr(initial, net).weight), net
    assert not torch.equal(model.assemblies.projection, initial.assemblies.projection)


@pytest.mark.parametrize("reading, io", [("joints", 5), ("joints+hand", 11), ("hand", 6)])
def test_hand_path_reads_the_arm_the_recordings_came_from_and_checkpoints_it(tmp_path, reading, io) -> None:
    data = tiny_corpus(variants=1)
    options = replace(_tiny_options(), hand_path=reading, object_motion="none", selection_scenes=0)
    trained = train_end_to_end(data, prepare(data, tiny_config()), seed=1, options=options)
    config = trained.model.config
    arm = None if reading == "joints" else data.arm  # the paper's codes need no kinematics
    assert (config.somatosensory.io, config.proprioception, config.arm) == (io, reading, arm)
    model, _ = _describes_the_same_after_loading(trained, data, tmp_path)
    assert model.config.proprioception == reading


def _describes_the_same_after_loading(
    trained: TrainedModel, data: SequenceSet, tmp_path: Path
) -> tuple[MultiMTRNN, list[Description]]:
    """Save and load `trained`'s model: the first two recordings' activity and Csc states are
    bitwise the same; (loaded model, its descriptions)."""
    before = trained.model.describe_batch(data.proprioception[:2], data.vision[:2], trained.lexicon)
    checkpoint.save(trained.model, tmp_path / "m", trained.meta)
    model, _ = checkpoint.load(tmp_path / "m")
    after = model.describe_batch(data.proprioception[:2], data.vision[:2], trained.lexicon)
    for b, a in zip(before, after, strict=True):
        np.testing.assert_array_equal(b.activity, a.activity)
        np.testing.assert_array_equal(b.csc_s, a.csc_s)
        np.testing.assert_array_equal(b.csc_v, a.csc_v)
    return model, after


@pytest.mark.parametrize("reader, io_s", [("visual", 6), ("somatosensory", 8)])
def test_object_motion_is_checkpointed_and_described_the_same_after_loading(tmp_path, reader, io_s) -> None:
    data = tiny_corpus(variants=1)
    options = replace(_tiny_options(), hand_path="hand", object_motion=reader, selection_scenes=0)
    trained = train_end_to_end(data, prepare(data, tiny_config()), seed=1, options=options)
    config = trained.model.config
    assert (config.object_motion, config.somatosensory.io, config.visual.io) == (reader, io_s, 21)
    assert trained.meta["end_to_end"]["object_motion"] == reader
    model, after = _describes_the_same_after_loading(trained, data, tmp_path)
    assert model.config.object_motion == reader
    timeline = model.timeline(data.proprioception[0], data.vision[0], trained.lexicon)
    assert timeline.texts[-1] == after[0].text
    with pytest.raises(ValueError, match="needs vision_centroid"):
        EndToEndOptions(object_motion="visual", vision_centroid=False)
    with pytest.raises(ValueError, match="object_motion must be one of"):
        EndToEndOptions(object_motion="both")


def test_hand_path_needs_the_arm_of_the_recordings() -> None:
    data = replace(tiny_corpus(variants=1), arm=None)  # nothing to read the hand's path through
    options = replace(_tiny_options(), hand_path="joints+hand", selection_scenes=0)
    with pytest.raises(ValueError, match="arm"):
        train_end_to_end(data, prepare(data, tiny_config()), seed=1, options=options)
    with pytest.raises(ValueError, match="hand_path must be"):
        EndToEndOptions(hand_path="elbow")
