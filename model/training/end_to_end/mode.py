"""Training mode `end_to_end`: the MultiMTRNN learns to describe scenes it has never seen.

The paper's staged recipe (`faithful`) fits the cell assemblies (CAs) afterwards, by LMS, from
the encoders' self-organised c_s,T and c_v,T to per-sequence c_a,0 (eqs. 16-17); on novel scenes
it almost never produces the right sentence. In the authors' 2020 follow-up the CAs and the
encoders learn through the auditory loss instead. This mode does that, and adds what keeps the
perception codes' action, colour and shape; every addition is a named field of `EndToEndOptions`,
stored in the checkpoint meta under "end_to_end" and measured in docs/experiments/end_to_end.md.

Generation stays the model's path (`MultiMTRNN.describe`):

    MTRNN_s.abstract(proprioception) -> c_s,T     MTRNN_v.abstract(vision) -> c_v,T
    WordAssemblies(c_s,T, c_v,T):
        z = W_s f(c_s,T) + W_v f(c_v,T) + b          eq. (17), one unit per heard word
        p = softmax of z within each slot           (or a logistic per word), winner-take-all
        c_a,0 = E p + e                             the assemblies' projection into MTRNN_a
    MTRNN_a.generate(c_a,0) -> activity -> phonemes -> text

The word units are the learner's own: `WordSlots.from_utterances` reads them off the utterances
it heard (a word said in every utterance carries nothing; words that always occur together form
one phrase, e.g. "show me"; the k-th remaining phrase of a sentence is slot k).

Training, top to bottom (`train_end_to_end`):
1. Auditory stage: MTRNN_a and the CAs' projection (E, e) learn the KLD of the utterances
   (3.1.3) with teacher forcing alpha (eq. 5), starting from c_a,0 = E p* + e where p* are the
   words the teacher said: the CAs are trained through the auditory loss. All recordings of a
   scene share an utterance and a p*, so each distinct utterance is one sequence (with the same
   number of recordings per scene the mean loss, hence every RPROP sign, is unchanged).
   The learner then listens to itself (`combinations_said`): spoken to with every combination of
   heard words, one per slot, does MTRNN_a say those words? If not (RPROP can leave it unable to
   put, say, "green" before "apple" when it never heard them together), it starts again from new
   weights, up to `auditory_attempts` times, and keeps the generator that said the most. It also
   checks itself every `auditory_check_every` epochs and stops as soon as it says them all.
2. Perception stage: MTRNN_s, MTRNN_v and the word units (W_s, W_v, b) learn which words the
   teacher said (the learner hears the utterance), from the Csc states at `word_points` points
   between `word_from` and 100 % of each sequence. The encoders read standardised inputs
   (`InputNormaliser`, folded into their input weights afterwards). `selection_scenes` training
   scenes are held out: every `select_every` epochs each encoder's word units get one gain per
   slot fitted on them (`calibrate`: how far that sense can be trusted for that slot on unseen
   scenes), and the state with the best held-out accuracy is kept, gains folded into W_s, W_v.
   With `modality_experts` each encoder's units learn on their own (a product of experts).
   With `recombine`, the word loss also covers recombined recordings (MTRNN_s reading one
   recording, MTRNN_v another) whose slot-k word is learned to come with one of the two senses
   (`recombination_loss`): nobody tells the learner which sense carries which slot, but an
   encoder that memorised what it cannot perceive is wrong on recombined pairs, so it unlearns it.
   `weight_decay` adds an L2 penalty on the weight matrices; `average_from` makes the final
   perception weights the running mean of the weights over the last epochs (Polyak averaging);
   `time_warp` replays every recording at its own random speed each epoch (another teacher's tempo).
   For colour x shape pairs never seen (issue 16, `factors.py`): `recombine_objects` adds the word
   loss of recoloured recordings (the colour columns of another recording of another colour, its
   colour word with them), and `factorised_vision` cuts MTRNN_v into a colour and a shape pathway
   whose Csc only the colour and the shape slot's word units read. For recordings made elsewhere
   (issue 12): `hand_path` lets MTRNN_s read the hand's path in the torso frame (forward kinematics
   of the recordings' arm, `model.encoding.kinematics`) beside or instead of the joint codes; the
   path does not depend on which of the redundant arm's joint configurations reached it.
3. Joint stage (`joint_epochs`): perception -> CAs -> MTRNN_a, everything through the auditory
   loss (plus the word loss when on). With `word_loss` off this is the only stage: the plain
   2020-style end-to-end training that the options are measured against.
"""

from __future__ import annotations

import time
from dataclasses import asdict, replace

import torch

from model.assemblies import WordAssemblies
from model.config import MultiMTRNNConfig
from model.data import SequenceSet
from model.encoding.kinematics import HAND_PATH_COLUMNS, ArmChain
from model.encoding.vision import FEATURES as WITH_CENTROID
from model.multimtrnn import MOTION_COLUMNS, MultiMTRNN
from model.training.common import (
    MultiMTRNNMode,
    ProgressFn,
    ProgressReporter,
    TrainedModel,
    base_meta,
    make_batch,
)
from model.training.end_to_end.augmentation import InputNormaliser, PerceptionBatch
from model.training.end_to_end.factors import colour_and_shape_slots, csc_pathways, factorise
from model.training.end_to_end.generator import train_generator
from model.training.end_to_end.options import EndToEndOptions
from model.training.end_to_end.perception import selection_split, train_joint_stage, train_perception_stage
from model.training.end_to_end.words import WordSlots


def word_assemblies(
    config: MultiMTRNNConfig,
    slots: WordSlots,
    options: EndToEndOptions,
    seed: int,
    factors: dict | None = None,
) -> WordAssemblies:
    """The CAs with one word unit per heard phrase (`model.assemblies.WordAssemblies`); with
    `factorised_vision` the colour slot's units read the colour pathway's c_v, the shape slot's
    the shape pathway's (`factors`: the slots of `colour_and_shape_slots`)."""
    readout = None
    if options.factorised_vision and factors:
        readout = [None] * len(slots.sizes)
        readout[factors["colour_slot"]], readout[factors["shape_slot"]] = csc_pathways(config.visual)
    return WordAssemblies(
        config.somatosensory.csc,
        config.visual.csc,
        config.auditory.csc,
        [list(s) for s in slots.slots],
        slot_softmax=options.slot_softmax,
        hard=options.hard_words,
        weight_init=config.auditory.weight_init,
        seed=seed + 4,
        visual_readout=readout,
    )


def read_hand_path(config: MultiMTRNNConfig, data: SequenceSet, reading: str) -> None:
    """Let MTRNN_s read the hand's path (`hand_path`) through the arm the recordings came from."""
    if data.arm is None:
        raise ValueError("hand_path needs the arm the joint angles belong to (SequenceSet.arm)")
    arm = ArmChain.from_dict(data.arm)
    io = (arm.joints if reading == "joints+hand" else 0) + HAND_PATH_COLUMNS
    config.somatosensory = replace(config.somatosensory, io=io)
    config.proprioception, config.arm = reading, data.arm


def object_factors(data: SequenceSet, slots: WordSlots, options: EndToEndOptions) -> dict:
    """Which heard slots the colour and the shape columns tell, when an option needs them."""
    if options.recombine_objects <= 0 and not options.factorised_vision:
        return {}
    if len(slots.sizes) < 2:
        raise ValueError("recombine_objects and factorised_vision need a colour and a shape slot")
    colour, shape = colour_and_shape_slots(slots.one_hot(data.utterances), slots.sizes, data.vision)
    return {"colour_slot": colour, "shape_slot": shape}


def _train(
    data: SequenceSet,
    config: MultiMTRNNConfig,
    seed: int,
    progress: ProgressFn | None,
    options: EndToEndOptions,
) -> TrainedModel:
    columns = data.vision[0].shape[1]
    config.visual = replace(config.visual, io=min(columns, WITH_CENTROID) if options.vision_centroid else 19)
    if options.object_motion != "none" and columns < WITH_CENTROID:
        raise ValueError(f"object_motion needs the object's centroid among the {columns} vision features")
    config.object_motion = options.object_motion
    if options.hand_path != "joints":
        read_hand_path(config, data, options.hand_path)
    if options.object_motion == "somatosensory":
        config.somatosensory = replace(config.somatosensory, io=config.somatosensory.io + MOTION_COLUMNS)
    slots = WordSlots.from_utterances(data.utterances)
    factors = object_factors(data, slots, options)
    assemblies = word_assemblies(config, slots, options, seed, factors)
    model = MultiMTRNN(config, assemblies=assemblies, seed=seed)
    if options.factorised_vision:
        factorise(model.visual)
    batch = make_batch(data, config)
    history: list[dict] = []
    report = ProgressReporter(progress, config.training.progress_every, history)
    seconds: dict[str, float] = {}
    normalisers = None
    if options.normalise_inputs:
        normalisers = (
            InputNormaliser.fit(batch.proprioception, batch.proprioception_lengths),
            InputNormaliser.fit(batch.vision, batch.vision_lengths),
        )
    perception = PerceptionBatch(
        normalisers[0](batch.proprioception) if normalisers else batch.proprioception,
        batch.proprioception_lengths,
        normalisers[1](batch.vision) if normalisers else batch.vision,
        batch.vision_lengths,
        slots.one_hot(data.utterances),
    )
    meta: dict = {"selection": {}, **({"factors": factors} if factors else {})}
    if options.word_loss:
        meta.update(_word_stages(data, model, slots, perception, options, report, seconds, seed, factors))
    if options.joint_epochs > 0:
        start = time.perf_counter()
        train_joint_stage(model, assemblies, perception, batch.utterances, options, report)
        seconds["joint"] = time.perf_counter() - start
    if normalisers is not None:
        normalisers[0].fold_into(model.somatosensory)
        normalisers[1].fold_into(model.visual)
    meta = {**base_meta(data, config, model, "end_to_end", seed), "end_to_end": asdict(options), **meta}
    meta["seconds"] = seconds
    model.eval()
    return TrainedModel(model, history, meta)


train_end_to_end = MultiMTRNNMode(_train, EndToEndOptions)


def _word_stages(
    data: SequenceSet,
    model: MultiMTRNN,
    slots: WordSlots,
    perception: PerceptionBatch,
    options: EndToEndOptions,
    report: ProgressReporter,
    seconds: dict[str, float],
    seed: int,
    factors: dict,
) -> dict:
    """Stages 1 and 2: the generator learns to say the heard words, then perception learns which
    words were heard. Returns their meta ("generator", "selection")."""
    assemblies = model.assemblies
    start = time.perf_counter()
    utterances = list(dict.fromkeys(data.utterances))  # one sequence per distinct utterance
    generator_check = train_generator(model, assemblies, utterances, slots, options, report, seed)
    seconds["auditory"] = time.perf_counter() - start

    start = time.perf_counter()
    held_out = None
    fit = perception
    if options.selection_scenes > 0:
        fit_idx, held_idx = selection_split(data, slots, options.selection_scenes, seed)
        if held_idx:
            fit, held_out = perception.subset(fit_idx), perception.subset(held_idx)
    selection = train_perception_stage(
        model,
        assemblies,
        fit,
        held_out,
        options,
        report,
        torch.Generator().manual_seed(seed + 5),
        colour_slot=factors.get("colour_slot"),
    )
    seconds["perception"] = time.perf_counter() - start
    return {"selection": selection, "generator": generator_check}
