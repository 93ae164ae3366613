"""Stages 2 and 3 of `end_to_end`: perception learns which words the teacher said (with held-out
selection and recombined pairs), then everything learns through the auditory loss."""

from __future__ import annotations

import logging

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor, nn

from model.assemblies import WordAssemblies
from model.data import SequenceSet, scene_key
from model.mtrnn import kl_divergence
from model.multimtrnn import MultiMTRNN
from model.training.common import ProgressReporter, make_optimiser
from model.training.end_to_end.augmentation import PerceptionBatch, csc_at, reading_points
from model.training.end_to_end.factors import recoloured
from model.training.end_to_end.options import EndToEndOptions
from model.training.end_to_end.words import WordSlots

log = logging.getLogger(__name__)


def selection_split(
    data: SequenceSet, slots: WordSlots, scenes: int, seed: int
) -> tuple[list[int], list[int]]:
    """Hold out up to `scenes` training scenes (all their recordings) for model selection, keeping
    every word heard in at least two remaining scenes. Returns (fit, held-out) recording indices."""
    keys = [scene_key(rid) for rid in data.ids]
    scene_words = {k: tuple(slots.indices(u)) for k, u in zip(keys, data.utterances, strict=True)}
    remaining = {
        (slot, word): sum(1 for w in scene_words.values() if w[slot] == word)
        for w in scene_words.values()
        for slot, word in enumerate(w)
    }
    held: set[str] = set()
    ordered = sorted(scene_words)
    for i in np.random.default_rng([seed, 7]).permutation(len(ordered)):
        key = ordered[i]
        words = list(enumerate(scene_words[key]))
        if len(held) < scenes and all(remaining[w] > 2 for w in words):
            held.add(key)
            for w in words:
                remaining[w] -= 1
    fit = [i for i, k in enumerate(keys) if k not in held]
    return fit, [i for i, k in enumerate(keys) if k in held]


def perception_logits(
    model: MultiMTRNN, assemblies: WordAssemblies, data: PerceptionBatch, points: int, start: float
) -> tuple[Tensor, Tensor]:
    """Each encoder's share of eq. (17) at the reading points: z_s, z_v [B, points, words]."""
    c_s = csc_at(
        model.somatosensory,
        data.proprioception,
        data.proprioception_lengths,
        reading_points(data.proprioception_lengths, points, start),
    )
    c_v = csc_at(
        model.visual, data.vision, data.vision_lengths, reading_points(data.vision_lengths, points, start)
    )
    return assemblies.modality_logits(c_s, c_v)


def calibrate(
    assemblies: WordAssemblies, z_s: Tensor, z_v: Tensor, heard: Tensor
) -> tuple[Tensor, Tensor, float]:
    """Gains g >= 0 per slot and encoder minimising the held-out word loss of g_s z_s + g_v z_v:
    how far each encoder's words can be trusted on scenes it did not learn from.

    Returns (gain_s, gain_v) per word unit and the held-out accuracy (all slots right)."""
    raw = torch.zeros(2, len(assemblies.sizes), requires_grad=True)  # softplus(raw + 0.5413) = 1
    optimiser = torch.optim.LBFGS([raw], max_iter=50, line_search_fn="strong_wolfe")
    sizes = torch.tensor(assemblies.sizes)

    def gains() -> tuple[Tensor, Tensor]:
        g = F.softplus(raw + 0.5413).repeat_interleave(sizes, dim=1)
        return g[0], g[1]

    def closure() -> Tensor:
        optimiser.zero_grad()
        g_s, g_v = gains()
        loss = assemblies.word_loss(g_s * z_s + g_v * z_v, heard)
        loss.backward()
        return loss

    optimiser.step(closure)
    with torch.no_grad():
        g_s, g_v = gains()
        p = assemblies.word_activity(g_s * z_s + g_v * z_v, hard=True)
        right = (p * heard).sum(dim=-1) == len(assemblies.sizes)
    return g_s, g_v, right.float().mean().item()


def recombination_loss(
    assemblies: WordAssemblies,
    z_s: Tensor,
    z_v: Tensor,
    heard: Tensor,
    mix: Tensor,
    generator: torch.Generator,
    pairs: int,
) -> Tensor:
    """Word loss of recombined recordings: MTRNN_s reading recording A, MTRNN_v recording B.

    Which sense tells which slot is not given: slot k's word is A's with a learned probability
    sigmoid(mix_k) and B's otherwise, so the loss of slot k is
    -log(sigmoid(mix_k) p_k(w_A) + sigmoid(-mix_k) p_k(w_B)) with p = softmax of z_s(A) + z_v(B)
    (eq. 17). An encoder that memorised a slot it cannot perceive (the colour of each training
    motion) is then wrong on every pair whose other recording shows another colour.
    z_s, z_v: [B, points, words]; heard: [B, words]; mix: [slots]."""
    loss = z_s.new_zeros(())
    log_a, log_b = F.logsigmoid(mix), F.logsigmoid(-mix)
    for _ in range(pairs):
        other = torch.randperm(z_v.shape[0], generator=generator)
        z = z_s + z_v[other]
        parts = zip(
            z.split(assemblies.sizes, dim=-1),
            heard.split(assemblies.sizes, dim=-1),
            heard[other].split(assemblies.sizes, dim=-1),
            strict=True,
        )
        for k, (zk, ak, bk) in enumerate(parts):
            log_p = torch.log_softmax(zk, dim=-1)
            from_a = (ak[:, None, :] * log_p).sum(dim=-1) + log_a[k]
            from_b = (bk[:, None, :] * log_p).sum(dim=-1) + log_b[k]
            loss = loss - torch.logaddexp(from_a, from_b).mean()
    return loss / (pairs * len(assemblies.sizes))


def train_perception_stage(
    model: MultiMTRNN,
    assemblies: WordAssemblies,
    fit: PerceptionBatch,
    held_out: PerceptionBatch | None,
    options: EndToEndOptions,
    report: ProgressReporter,
    generator: torch.Generator,
    colour_slot: int | None = None,
) -> dict:
    """Stage 2: encoders and word units learn the heard words at the reading points (and on
    recombined pairs, `recombination_loss`; on recoloured recordings of the `colour_slot` with
    `recombine_objects`). With a held-out set, every `select_every` epochs the
    encoders' gains are calibrated on it and the best state (held-out accuracy, then loss) is
    kept, its gains folded into W_s, W_v; otherwise the final (or averaged) state is kept."""
    params = [
        *model.somatosensory.parameters(),
        *model.visual.parameters(),
        assemblies.weight_s,
        assemblies.bias_s,
        assemblies.weight_v,
        assemblies.bias_v,
    ]
    mix = nn.Parameter(torch.zeros(len(assemblies.sizes)))  # which sense tells each slot (recombined)
    if options.recombine > 0:
        params.append(mix)
    optimiser = make_optimiser([{"params": params}], model.config.training)
    epochs = options.perception_epochs
    best: dict = {"accuracy": -1.0}
    matrices = [p for p in params if p.ndim == 2]
    average = _Average(model, options.average_from, epochs)
    for epoch in range(1, epochs + 1):
        optimiser.zero_grad()
        loss = _perception_loss(model, assemblies, fit, mix, matrices, options, generator, colour_slot)
        loss.backward()
        optimiser.step()
        report("perception", epoch, epochs, loss.item())
        average.add(epoch)
        if held_out is not None and (epoch % options.select_every == 0 or epoch == epochs):
            best = _select(model, assemblies, held_out, epoch, best)
    recombined = {"sense_of_slot_is_s": torch.sigmoid(mix).tolist()} if options.recombine > 0 else {}
    if average.state:
        model.load_state_dict(average.state)
    if held_out is None:
        return recombined
    return {**_keep_best(model, assemblies, best), **recombined}


def _perception_loss(
    model: MultiMTRNN,
    assemblies: WordAssemblies,
    fit: PerceptionBatch,
    mix: Tensor,
    matrices: list[Tensor],
    options: EndToEndOptions,
    generator: torch.Generator,
    colour_slot: int | None = None,
) -> Tensor:
    """One epoch's loss: the word loss on the (augmented) recordings, on recombined pairs, on
    recoloured recordings, and the weight decay."""
    seen = fit.with_noise(options.input_noise, generator) if options.input_noise > 0 else fit
    if options.time_warp > 0:
        seen = seen.time_warped(options.time_warp, generator)
    if options.vision_window > 0:
        seen = seen.vision_windows(options.vision_window, generator)
    z_s, z_v = perception_logits(model, assemblies, seen, options.word_points, options.word_from)
    target = fit.heard[:, None, :]
    if options.modality_experts:
        loss = assemblies.word_loss(z_s, target) + assemblies.word_loss(z_v, target)
    else:
        loss = assemblies.word_loss(z_s + z_v, target)
    if options.recombine > 0:
        loss = loss + options.recombine * recombination_loss(
            assemblies, z_s, z_v, fit.heard, mix, generator, options.recombine_pairs
        )
    if options.recombine_objects > 0 and colour_slot is not None:
        loss = loss + options.recombine_objects * recolouring_loss(
            model, assemblies, seen, z_s, colour_slot, options, generator
        )
    if options.weight_decay > 0:
        loss = loss + options.weight_decay * sum((w**2).sum() for w in matrices)
    return loss


def recolouring_loss(
    model: MultiMTRNN,
    assemblies: WordAssemblies,
    seen: PerceptionBatch,
    z_s: Tensor,
    colour_slot: int,
    options: EndToEndOptions,
    generator: torch.Generator,
) -> Tensor:
    """Word loss of recoloured recordings (`factors.recoloured`): MTRNN_s reads the recording,
    MTRNN_v the recording with another recording's colour, and the colour word heard is the
    donor's: every colour with every shape, also the pairs no teacher showed."""
    vision, heard = recoloured(
        seen.vision, seen.vision_lengths, seen.heard, assemblies.sizes, colour_slot, generator
    )
    c_v = csc_at(
        model.visual,
        vision,
        seen.vision_lengths,
        reading_points(seen.vision_lengths, options.word_points, options.word_from),
    )
    return assemblies.word_loss(z_s + assemblies.visual_logits(c_v), heard[:, None, :])


class _Average:
    """Running mean of the model's weights from a fraction of the epochs on (Polyak averaging)."""

    def __init__(self, model: MultiMTRNN, average_from: float, epochs: int) -> None:
        self.model = model
        self.start = max(1, round(average_from * epochs)) if average_from > 0 else 0
        self.state: dict[str, Tensor] = {}

    @torch.no_grad()
    def add(self, epoch: int) -> None:
        if not self.start or epoch < self.start:
            return
        n = epoch - self.start
        for k, v in self.model.state_dict().items():
            self.state[k] = v.detach().clone() if n == 0 else self.state[k] + (v - self.state[k]) / (n + 1)


def _select(
    model: MultiMTRNN, assemblies: WordAssemblies, held_out: PerceptionBatch, epoch: int, best: dict
) -> dict:
    """Calibrate the encoders' gains on the held-out scenes; this state if it is at least as good."""
    with torch.no_grad():
        h_s, h_v = perception_logits(model, assemblies, held_out, 1, 1.0)
    g_s, g_v, accuracy = calibrate(assemblies, h_s[:, 0], h_v[:, 0], held_out.heard)
    if accuracy < best["accuracy"]:
        return best
    state = {k: v.detach().clone() for k, v in model.state_dict().items()}
    return {"accuracy": accuracy, "epoch": epoch, "state": state, "gains": (g_s, g_v)}


def _keep_best(model: MultiMTRNN, assemblies: WordAssemblies, best: dict) -> dict:
    """Load the selected state and fold its gains into W_s, W_v; its meta."""
    model.load_state_dict(best["state"])
    with torch.no_grad():
        g_s, g_v = best["gains"]
        assemblies.weight_s *= g_s[:, None]
        assemblies.bias_s *= g_s
        assemblies.weight_v *= g_v[:, None]
        assemblies.bias_v *= g_v
    log.info("perception: held-out accuracy %.3f at epoch %d", best["accuracy"], best["epoch"])
    return {
        "epoch": best["epoch"],
        "held_out_accuracy": best["accuracy"],
        "gains_s": g_s.tolist(),
        "gains_v": g_v.tolist(),
    }


def train_joint_stage(
    model: MultiMTRNN,
    assemblies: WordAssemblies,
    data: PerceptionBatch,
    utterances: Tensor,
    options: EndToEndOptions,
    report: ProgressReporter,
) -> None:
    """Stage 3: perception -> CAs -> MTRNN_a, all weights through the auditory loss (+ words)."""
    training = model.config.training
    optimiser = make_optimiser([{"params": list(model.parameters())}], training)
    for epoch in range(1, options.joint_epochs + 1):
        optimiser.zero_grad()
        c_s = model.somatosensory.abstract(data.proprioception, data.proprioception_lengths)
        c_v = model.visual.abstract(data.vision, data.vision_lengths)
        z = assemblies.word_logits(c_s, c_v)  # eq. (17)
        c_a0 = assemblies.speak(assemblies.word_activity(z, hard=False))
        output = model.auditory.generate(c_a0, utterances.shape[1], teacher=utterances, alpha=training.alpha)
        loss = kl_divergence(utterances, output)
        if options.word_loss:
            loss = loss + assemblies.word_loss(z, data.heard)
        loss.backward()
        optimiser.step()
        report("joint", epoch, options.joint_epochs, loss.item())
