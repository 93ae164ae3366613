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
3. Joint stage (`joint_epochs`): perception -> CAs -> MTRNN_a, everything through the auditory
   loss (plus the word loss when on). With `word_loss` off this is the only stage: the plain
   2020-style end-to-end training that the options are measured against.
"""

from __future__ import annotations

import copy
import itertools
import logging
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, fields, replace

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor, nn

from model.config import MultiMTRNNConfig, mode_options
from model.data import SequenceSet
from model.encoding.utterance import Lexicon, decode_text
from model.experiments.evaluation import scene_key
from model.mtrnn import MTRNN, kl_divergence, scaled_logistic
from model.multimtrnn import MultiMTRNN, register_assemblies
from model.training import (
    ProgressFn,
    ProgressReporter,
    TrainedModel,
    base_meta,
    encode_utterances,
    make_batch,
    make_optimiser,
    register_mode,
)

log = logging.getLogger(__name__)


@dataclass
class EndToEndOptions:
    """The named additions of `end_to_end` (module docstring); defaults are the measured best."""

    word_loss: bool = True  # perception learns which words the teacher said (stage 2)
    word_points: int = 4  # Csc states read at this many points of each sequence ...
    word_from: float = 0.85  # ... evenly from this fraction of its length to its end (0.3 mixed up actions)
    slot_softmax: bool = True  # one word per slot (softmax); False: a logistic per word
    modality_experts: bool = False  # each encoder's word units learn alone; eq. (17) sums them
    hard_words: bool = True  # winner-take-all word units when describing
    vision_centroid: bool = True  # MTRNN_v also reads the object's centroid (21 inputs, not 19)
    normalise_inputs: bool = True  # standardise encoder inputs while training (`InputNormaliser`)
    selection_scenes: int = 0  # training scenes held out to calibrate and select perception
    select_every: int = 10  # epochs between two selections
    input_noise: float = 0.0  # std of Gaussian noise on the (normalised) encoder inputs, per epoch
    vision_window: int = 0  # > 0: MTRNN_v learns from a random window of this many frames per epoch
    time_warp: float = 0.0  # > 0: every epoch each recording replays at a random speed in [1 - w, 1 + w]
    recombine: float = 1.0  # weight of the word loss on recombined pairs (`recombination_loss`)
    recombine_pairs: int = 1  # recombined pairings (random permutations) per epoch
    weight_decay: float = 1e-4  # L2 penalty on the encoders' and word units' weight matrices
    average_from: float = 0.5  # > 0: perception weights averaged from this fraction of epochs on
    auditory_epochs: int = 1500  # stage 1, at most, per attempt (docs/experiments/end_to_end.md, rounds 3-4)
    auditory_attempts: int = 3  # MTRNN_a restarts from new weights until it says every word combination
    auditory_check_every: int = 250  # > 0: it checks itself this often and stops once it says them all
    perception_epochs: int = 300  # stage 2 (the held-out selection keeps the best epoch)
    joint_epochs: int = 0  # stage 3

    def __post_init__(self) -> None:
        if self.average_from > 0 and self.selection_scenes > 0:
            raise ValueError("average_from needs selection_scenes = 0 (the average is the final state)")
        if self.recombine > 0 and not self.slot_softmax:
            raise ValueError("recombine needs slot_softmax word units")


# --- the words the learner heard -----------------------------------------------------------------


def _words(text: str) -> list[str]:
    return re.findall(r"[a-z']+", text.lower())


@dataclass(frozen=True)
class WordSlots:
    """Slots of phrases read off heard utterances: slot k holds every phrase heard k-th."""

    slots: tuple[tuple[str, ...], ...]

    @classmethod
    def from_utterances(cls, utterances: Sequence[str]) -> WordSlots:
        sentences = [_words(u) for u in utterances]
        heard_in: dict[str, frozenset[int]] = {}
        for i, words in enumerate(sentences):
            for w in words:
                heard_in[w] = heard_in.get(w, frozenset()) | {i}
        phrased = [cls._phrases(words, heard_in, len(sentences)) for words in sentences]
        counts = {len(p) for p in phrased}
        if len(counts) != 1:
            raise ValueError(f"utterances have different numbers of informative phrases: {sorted(counts)}")
        slots = tuple(tuple(sorted({p[k] for p in phrased})) for k in range(counts.pop()))
        return cls(slots)

    @staticmethod
    def _phrases(words: list[str], heard_in: dict[str, frozenset[int]], n: int) -> list[str]:
        """Drop words said in every utterance; join neighbours always heard together."""
        phrases: list[list[str]] = []
        previous = None
        for w in words:
            if len(heard_in.get(w, ())) == n:
                previous = None
                continue
            if previous is not None and heard_in.get(previous) == heard_in.get(w):
                phrases[-1].append(w)
            else:
                phrases.append([w])
            previous = w
        return [" ".join(p) for p in phrases]

    @property
    def sizes(self) -> list[int]:
        return [len(s) for s in self.slots]

    def indices(self, utterance: str) -> list[int]:
        """Index of the heard phrase within each slot (ValueError if one is unknown)."""
        text = " ".join(_words(utterance))
        out = []
        for slot in self.slots:
            found = [k for k, phrase in enumerate(slot) if re.search(rf"\b{re.escape(phrase)}\b", text)]
            if len(found) != 1:
                raise ValueError(f"{utterance!r} has no single phrase of slot {slot}")
            out.append(found[0])
        return out

    def one_hot(self, utterances: Sequence[str]) -> Tensor:
        """p*: the heard words as word-unit activity [B, sum(sizes)], one 1 per slot."""
        return self.activity([self.indices(u) for u in utterances])

    def activity(self, phrases: Sequence[Sequence[int]]) -> Tensor:
        """Word-unit activity [B, sum(sizes)] of phrase indices per slot [B][slots], one 1 per slot."""
        out = torch.zeros(len(phrases), sum(self.sizes))
        offsets = np.cumsum([0, *self.sizes[:-1]])
        for i, indices in enumerate(phrases):
            for offset, k in zip(offsets, indices, strict=True):
                out[i, offset + k] = 1.0
        return out


# --- the cell assemblies with word units ----------------------------------------------------------


@register_assemblies("words")
class WordAssemblies(nn.Module):
    """CAs with a layer of word units between the perception Csc and c_a,0 (module docstring)."""

    kind = "words"

    def __init__(
        self,
        csc_s: int,
        csc_v: int,
        csc_a: int,
        slots: list[list[str]],
        slot_softmax: bool = True,
        hard: bool = True,
        weight_init: float = 0.025,
        seed: int = 0,
    ) -> None:
        super().__init__()
        self._kwargs = {
            "csc_s": csc_s,
            "csc_v": csc_v,
            "csc_a": csc_a,
            "slots": [list(s) for s in slots],
            "slot_softmax": slot_softmax,
            "hard": hard,
            "weight_init": weight_init,
            "seed": seed,
        }
        self.sizes = [len(s) for s in slots]
        self.slot_softmax, self.hard = slot_softmax, hard
        words = sum(self.sizes)
        g = torch.Generator().manual_seed(seed)

        def uniform(*shape: int) -> nn.Parameter:
            return nn.Parameter((torch.rand(*shape, generator=g) * 2 - 1) * weight_init)

        self.weight_s, self.bias_s = uniform(words, csc_s), uniform(words)  # W_s and its share of b
        self.weight_v, self.bias_v = uniform(words, csc_v), uniform(words)  # W_v and its share of b
        self.projection, self.projection_bias = uniform(csc_a, words), uniform(csc_a)  # E, e

    @property
    def words(self) -> list[str]:
        return [w for s in self._kwargs["slots"] for w in s]

    @torch.no_grad()
    def redraw_projection(self, generator: torch.Generator) -> None:
        """New initial E, e (a fresh start of the auditory stage)."""
        for p in (self.projection, self.projection_bias):
            p.copy_((torch.rand(p.shape, generator=generator) * 2 - 1) * self._kwargs["weight_init"])

    def init_kwargs(self) -> dict:
        return copy.deepcopy(self._kwargs)

    def modality_logits(self, c_s: Tensor, c_v: Tensor) -> tuple[Tensor, Tensor]:
        """Each encoder's share of eq. (17): W_s f(c_s) + b_s and W_v f(c_v) + b_v [..., words]."""
        return (
            scaled_logistic(c_s) @ self.weight_s.T + self.bias_s,
            scaled_logistic(c_v) @ self.weight_v.T + self.bias_v,
        )

    def word_logits(self, c_s: Tensor, c_v: Tensor) -> Tensor:
        """z of eq. (17) for the word units."""
        z_s, z_v = self.modality_logits(c_s, c_v)
        return z_s + z_v

    def word_activity(self, z: Tensor, hard: bool) -> Tensor:
        """p: softmax within each slot (or a logistic per word); one-hot winners when `hard`."""
        if not self.slot_softmax:
            p = torch.sigmoid(z)
            return (p > 0.5).to(p.dtype) if hard else p
        parts = []
        for zk in z.split(self.sizes, dim=-1):
            pk = torch.softmax(zk, dim=-1)
            parts.append(F.one_hot(pk.argmax(dim=-1), pk.shape[-1]).to(pk.dtype) if hard else pk)
        return torch.cat(parts, dim=-1)

    def speak(self, p: Tensor) -> Tensor:
        """c_a,0 = E p + e."""
        return p @ self.projection.T + self.projection_bias

    def forward(self, c_s: Tensor, c_v: Tensor) -> Tensor:
        return self.speak(self.word_activity(self.word_logits(c_s, c_v), self.hard))

    def word_loss(self, z: Tensor, target: Tensor) -> Tensor:
        """Cross-entropy of the word units against the heard words p* (broadcast over points)."""
        target = target.expand_as(z)
        if not self.slot_softmax:
            return F.binary_cross_entropy_with_logits(z, target)
        loss = z.new_zeros(())
        for zk, tk in zip(z.split(self.sizes, dim=-1), target.split(self.sizes, dim=-1), strict=True):
            loss = loss - (tk * torch.log_softmax(zk, dim=-1)).sum(dim=-1).mean()
        return loss / len(self.sizes)


# --- training ------------------------------------------------------------------------------------


@dataclass
class InputNormaliser:
    """Per-input standardisation x' = (x - mean) / std from the training recordings.

    RPROP steps are sign-based, so an input that varies little (a shape distance) would otherwise
    need many epochs before it moves the encoder. The map is affine, so after training it is
    folded into the encoder's input weights and biases (`fold_into`): the trained MTRNN reads the
    raw features like any other and `MultiMTRNN.describe` needs nothing extra.
    """

    mean: Tensor  # [io]
    std: Tensor  # [io]

    @classmethod
    def fit(cls, inputs: Tensor, lengths: Tensor) -> InputNormaliser:
        valid = torch.arange(inputs.shape[1])[None, :] < lengths[:, None]
        steps = inputs[valid]
        return cls(steps.mean(dim=0), steps.std(dim=0).clamp(min=1e-3))

    def __call__(self, inputs: Tensor) -> Tensor:
        return (inputs - self.mean) / self.std

    @torch.no_grad()
    def fold_into(self, net: MTRNN) -> None:
        """W x' + b = (W / std) x + (b - W mean / std), for every unit the inputs reach (eq. 3)."""
        io = net.cfg.io
        w_in = net.masked_weight()[:, :io]
        net.bias -= w_in @ (self.mean / self.std)
        net.weight[:, :io] /= self.std


def reading_points(lengths: Tensor, points: int, start: float) -> Tensor:
    """Step indices [B, points], evenly from `start` of each sequence's length to its last step."""
    fractions = torch.linspace(start, 1.0, points) if points > 1 else torch.ones(1)
    steps = torch.ceil(fractions[None, :] * lengths[:, None].float()).long() - 1
    return steps.clamp(min=0)


def csc_at(net: MTRNN, inputs: Tensor, lengths: Tensor, steps: Tensor) -> Tensor:
    """Csc internal states of `net` reading `inputs` at `steps` [B, P] -> [B, P, csc]."""
    _, trajectory = net.abstract(inputs, lengths, return_states=True)
    rows = torch.arange(inputs.shape[0])[:, None]
    return trajectory[rows, steps][..., net.csc_slice]


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


@dataclass
class PerceptionBatch:
    """What the perception stage reads: padded (normalised) inputs and the heard words."""

    proprioception: Tensor
    proprioception_lengths: Tensor
    vision: Tensor
    vision_lengths: Tensor
    heard: Tensor  # p* [B, words]

    def subset(self, idx: list[int]) -> PerceptionBatch:
        return PerceptionBatch(*(getattr(self, f.name)[idx] for f in fields(self)))

    def with_noise(self, std: float, generator: torch.Generator) -> PerceptionBatch:
        """The same recordings with Gaussian noise of `std` on every input."""

        def noisy(x: Tensor) -> Tensor:
            return x + std * torch.randn(x.shape, generator=generator)

        return replace(self, proprioception=noisy(self.proprioception), vision=noisy(self.vision))

    def time_warped(self, warp: float, generator: torch.Generator) -> PerceptionBatch:
        """Each recording (both senses) replayed at its own random speed in [1 - warp, 1 + warp],
        by linear interpolation between steps: the tempo of another teacher."""
        speed = 1 + warp * (2 * torch.rand(len(self.heard), generator=generator) - 1)

        def replay(x: Tensor, lengths: Tensor) -> tuple[Tensor, Tensor]:
            new_lengths = (lengths / speed).round().long().clamp(min=2)
            last = (lengths - 1)[:, None].float()
            at = torch.arange(int(new_lengths.max()))[None, :] * last / (new_lengths - 1)[:, None]
            at = torch.minimum(at, last)
            before = at.floor().long()
            after = torch.minimum(before + 1, last.long())
            share = (at - before)[..., None]
            rows = torch.arange(len(x))[:, None]
            out = x[rows, before] * (1 - share) + x[rows, after] * share
            padding = torch.arange(out.shape[1])[None, :] >= new_lengths[:, None]
            return out.masked_fill(padding[..., None], 0.0), new_lengths

        proprioception, proprioception_lengths = replay(self.proprioception, self.proprioception_lengths)
        vision, vision_lengths = replay(self.vision, self.vision_lengths)
        return replace(
            self,
            proprioception=proprioception,
            proprioception_lengths=proprioception_lengths,
            vision=vision,
            vision_lengths=vision_lengths,
        )

    def vision_windows(self, width: int, generator: torch.Generator) -> PerceptionBatch:
        """Each recording's vision cut to a random window of `width` frames (whole if shorter)."""
        lengths = self.vision_lengths.clamp(max=width)
        room = (self.vision_lengths - lengths + 1).float()
        starts = (torch.rand(len(lengths), generator=generator) * room).long()
        steps = (starts[:, None] + torch.arange(int(lengths.max()))[None, :]).clamp(
            max=self.vision.shape[1] - 1
        )
        rows = torch.arange(len(lengths))[:, None]
        return replace(self, vision=self.vision[rows, steps], vision_lengths=lengths)


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
    for attempt in range(max(1, options.auditory_attempts)):
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
    model.auditory = best[0]
    with torch.no_grad():
        assemblies.projection.copy_(best[1])
        assemblies.projection_bias.copy_(best[2])
    log.info("auditory stage: word combinations said per attempt %s", attempts)
    return {"combinations_said": attempts, "epochs": epochs}


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
) -> dict:
    """Stage 2: encoders and word units learn the heard words at the reading points (and on
    recombined pairs, `recombination_loss`). With a held-out set, every `select_every` epochs the
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
    target = fit.heard[:, None, :]
    epochs = options.perception_epochs
    best: dict = {"accuracy": -1.0}
    matrices = [p for p in params if p.ndim == 2]
    average_start = max(1, round(options.average_from * epochs)) if options.average_from > 0 else 0
    averaged: dict[str, Tensor] = {}
    for epoch in range(1, epochs + 1):
        optimiser.zero_grad()
        seen = fit.with_noise(options.input_noise, generator) if options.input_noise > 0 else fit
        if options.time_warp > 0:
            seen = seen.time_warped(options.time_warp, generator)
        if options.vision_window > 0:
            seen = seen.vision_windows(options.vision_window, generator)
        z_s, z_v = perception_logits(model, assemblies, seen, options.word_points, options.word_from)
        if options.modality_experts:
            loss = assemblies.word_loss(z_s, target) + assemblies.word_loss(z_v, target)
        else:
            loss = assemblies.word_loss(z_s + z_v, target)
        if options.recombine > 0:
            loss = loss + options.recombine * recombination_loss(
                assemblies, z_s, z_v, fit.heard, mix, generator, options.recombine_pairs
            )
        if options.weight_decay > 0:
            loss = loss + options.weight_decay * sum((w**2).sum() for w in matrices)
        loss.backward()
        optimiser.step()
        report("perception", epoch, epochs, loss.item())
        if average_start and epoch >= average_start:
            with torch.no_grad():  # running mean of the weights (Polyak averaging)
                n = epoch - average_start
                for k, v in model.state_dict().items():
                    averaged[k] = v.detach().clone() if n == 0 else averaged[k] + (v - averaged[k]) / (n + 1)
        if held_out is not None and (epoch % options.select_every == 0 or epoch == epochs):
            with torch.no_grad():
                h_s, h_v = perception_logits(model, assemblies, held_out, 1, 1.0)
            g_s, g_v, accuracy = calibrate(assemblies, h_s[:, 0], h_v[:, 0], held_out.heard)
            if accuracy >= best["accuracy"]:
                state = {k: v.detach().clone() for k, v in model.state_dict().items()}
                best = {"accuracy": accuracy, "epoch": epoch, "state": state, "gains": (g_s, g_v)}
    recombined = {"sense_of_slot_is_s": torch.sigmoid(mix).tolist()} if options.recombine > 0 else {}
    if averaged:
        model.load_state_dict(averaged)
    if held_out is None:
        return recombined
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
        **recombined,
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


def train_end_to_end(
    data: SequenceSet,
    config: MultiMTRNNConfig,
    seed: int,
    progress: ProgressFn | None = None,
    options: EndToEndOptions | None = None,
) -> TrainedModel:
    """The `end_to_end` mode (module docstring); `config` comes from `model.training.prepare`."""
    options = options or mode_options(EndToEndOptions, config)
    training = config.training
    columns = data.vision[0].shape[1]
    config.visual = replace(config.visual, io=min(columns, 21) if options.vision_centroid else 19)
    slots = WordSlots.from_utterances(data.utterances)
    assemblies = WordAssemblies(
        config.somatosensory.csc,
        config.visual.csc,
        config.auditory.csc,
        [list(s) for s in slots.slots],
        slot_softmax=options.slot_softmax,
        hard=options.hard_words,
        weight_init=config.auditory.weight_init,
        seed=seed + 4,
    )
    model = MultiMTRNN(config, assemblies=assemblies, seed=seed)
    batch = make_batch(data, config)
    history: list[dict] = []
    report = ProgressReporter(progress, training.progress_every, history)
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
    selection: dict = {}

    if options.word_loss:
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
            model, assemblies, fit, held_out, options, report, torch.Generator().manual_seed(seed + 5)
        )
        seconds["perception"] = time.perf_counter() - start

    if options.joint_epochs > 0:
        start = time.perf_counter()
        train_joint_stage(model, assemblies, perception, batch.utterances, options, report)
        seconds["joint"] = time.perf_counter() - start

    if normalisers is not None:
        normalisers[0].fold_into(model.somatosensory)
        normalisers[1].fold_into(model.visual)
    meta = base_meta(data, config, model, "end_to_end", seed)
    meta["end_to_end"] = asdict(options)
    meta["selection"] = selection
    if options.word_loss:
        meta["generator"] = generator_check
    meta["seconds"] = seconds
    model.eval()
    return TrainedModel(model, history, meta)


register_mode("end_to_end", train_end_to_end)
