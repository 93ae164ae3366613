"""Stage 1 of `end_to_end`: MTRNN_a and the CAs' projection (E, e) learn to say the heard words,
and the learner listens to itself (`combinations_said`), restarting until it says every word
combination (`train_generator`)."""

from __future__ import annotations

import itertools
import logging
from collections.abc import Callable

import torch
from torch import Tensor

from model.assemblies import WordAssemblies
from model.encoding.utterance import Lexicon, decode_text
from model.mtrnn import MTRNN, kl_divergence
from model.multimtrnn import MultiMTRNN
from model.training.common import ProgressReporter, encode_utterances, make_optimiser
from model.training.end_to_end.options import EndToEndOptions
from model.training.end_to_end.words import WordSlots

log = logging.getLogger(__name__)


def train_auditory_stage(
    model: MultiMTRNN,
    assemblies: WordAssemblies,
    utterances: list[str],
    slots: WordSlots,
    epochs: int,
    report: ProgressReporter,
    says_all: Callable[[], bool] | None = None,
    check_every: int = 0,
) -> int:
    """Stage 1: MTRNN_a and the CAs' projection E, e learn the KLD (3.1.3) from c_a,0 = E p* + e.
    Every `check_every` epochs it stops early once `says_all()`. Returns the epochs trained."""
    training = model.config.training
    targets, _ = encode_utterances(utterances, model.config.generation_steps)
    words = slots.one_hot(utterances)
    params = [*model.auditory.parameters(), assemblies.projection, assemblies.projection_bias]
    optimiser = make_optimiser([{"params": params}], training)
    for epoch in range(1, epochs + 1):
        optimiser.zero_grad()
        c_a0 = assemblies.speak(words)
        output = model.auditory.generate(
            c_a0, targets.shape[1], teacher=targets, alpha=training.alpha
        )  # eq. (5)
        loss = kl_divergence(targets, output)
        loss.backward()
        optimiser.step()
        report("auditory", epoch, epochs, loss.item())
        if (
            says_all is not None
            and check_every > 0
            and epoch % check_every == 0
            and epoch < epochs
            and says_all()
        ):
            return epoch
    return epochs


@torch.no_grad()
def combinations_said(
    model: MultiMTRNN, assemblies: WordAssemblies, slots: WordSlots, lexicon: Lexicon
) -> float:
    """The learner listens to itself: the share of all word combinations (one heard phrase per
    slot, most never heard together) that MTRNN_a, spoken to from c_a,0 = E p + e, says back so
    that its decoded words hold exactly those phrases. Needs nothing but the heard words."""
    combinations = list(itertools.product(*(range(n) for n in slots.sizes)))
    activity = model.generate(assemblies.speak(slots.activity(combinations))).numpy()
    said = [_says(slots, decode_text(a, lexicon)[2], c) for a, c in zip(activity, combinations, strict=True)]
    return sum(said) / len(said)


def _says(slots: WordSlots, text: str, combination: tuple[int, ...]) -> bool:
    try:
        return slots.indices(text) == list(combination)
    except ValueError:  # a slot without exactly one heard phrase
        return False


def train_generator(
    model: MultiMTRNN,
    assemblies: WordAssemblies,
    utterances: list[str],
    slots: WordSlots,
    options: EndToEndOptions,
    report: ProgressReporter,
    seed: int,
) -> dict:
    """Stage 1 with self-monitoring: up to `auditory_attempts` fresh MTRNN_a (and E, e) are trained
    until one says every word combination back (`combinations_said`, also checked every
    `auditory_check_every` epochs to stop early); the best one is kept."""
    lexicon = Lexicon.from_sentences(utterances)

    def says_all() -> bool:
        return combinations_said(model, assemblies, slots, lexicon) == 1.0

    attempts: list[float] = []
    epochs: list[int] = []
    best: tuple[MTRNN, Tensor, Tensor] | None = None
    tries = max(1, options.auditory_attempts)
    for attempt in range(tries):
        report.attempt = (attempt + 1, tries)
        if attempt > 0:
            g = torch.Generator().manual_seed(seed * 7919 + attempt)
            model.auditory = MTRNN(model.config.auditory, g)
            assemblies.redraw_projection(g)
        epochs.append(
            train_auditory_stage(
                model,
                assemblies,
                utterances,
                slots,
                options.auditory_epochs,
                report,
                says_all,
                options.auditory_check_every,
            )
        )
        stopped_early = epochs[-1] < options.auditory_epochs  # only once it said them all
        said = 1.0 if stopped_early else combinations_said(model, assemblies, slots, lexicon)
        if best is None or said > max(attempts):
            best = (
                model.auditory,
                assemblies.projection.detach().clone(),
                assemblies.projection_bias.detach().clone(),
            )
        attempts.append(said)
        if said == 1.0:
            break
    assert best is not None
    report.attempt = None
    model.auditory = best[0]
    with torch.no_grad():
        assemblies.projection.copy_(best[1])
        assemblies.projection_bias.copy_(best[2])
    log.info("auditory stage: word combinations said per attempt %s", attempts)
    return {"combinations_said": attempts, "epochs": epochs}
