"""The multi-modal MTRNN of the paper (3.4, Fig. 4, eqs. 16-17).

MTRNN_s (proprioception) and MTRNN_v (vision) abstract their input sequences into final Csc
states c_s,T and c_v,T (context abstraction); the cell assemblies (CAs) map them to an initial
Csc state c_a,0 of MTRNN_a, which generates the utterance closed-loop (context bias):

    perception -> (c_s,T, c_v,T) -> assemblies -> c_a,0 -> MTRNN_a -> activity -> phonemes -> text

The assemblies are any module of `model.assemblies` (`forward(c_s, c_v) -> c_a0`, rebuilt from its
kind name by a checkpoint); `CellAssemblies` is the paper's and the default.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor, nn

from model.assemblies import CellAssemblies, WordAssemblies
from model.config import MultiMTRNNConfig
from model.encoding.kinematics import ArmChain, read_hand_path
from model.encoding.utterance import Lexicon, decode_text
from model.encoding.vision import FEATURES as WITH_CENTROID
from model.encoding.vision import VISUAL_FEATURES
from model.encoding.words import align
from model.mtrnn import MTRNN


def padded(x: Sequence[np.ndarray] | Tensor, lengths: Tensor | None, columns: int) -> tuple[Tensor, Tensor]:
    """A list of [T_i, F] arrays (`pad_sequences`), or a padded [B, T, F] tensor with optional
    lengths (all full by default), as [B, T, columns] and lengths [B]."""
    if isinstance(x, Tensor) and x.ndim == 3:
        if lengths is None:
            lengths = torch.full((x.shape[0],), x.shape[1])
        return x[..., :columns], lengths
    return pad_sequences(x, columns)


def somatosensory_inputs(
    proprioception: Sequence[np.ndarray] | Tensor,
    config: MultiMTRNNConfig,
    lengths: Tensor | None = None,
    vision: Sequence[np.ndarray] | Tensor | None = None,
) -> tuple[Tensor, Tensor]:
    """What MTRNN_s reads, padded [B, T, io], and the lengths [B], from the joint codes (4.1.1) of a
    list of [T_i, 5] arrays or a padded [B, T, 5] tensor with lengths: by `config.proprioception`
    the codes themselves (the paper), the codes and the hand's path read through `config.arm`
    (`model.encoding.kinematics`), or the hand's path alone; with `config.object_motion` =
    "somatosensory" the object's motion (`object_motion`) from `vision` (on the same time grid) after
    them."""
    arm = None if config.proprioception == "joints" else ArmChain.from_dict(config.arm or {})
    moving = config.object_motion == "somatosensory"
    joints = arm.joints if arm is not None else config.somatosensory.io - MOTION_COLUMNS * moving
    p, lengths = padded(proprioception, lengths, joints)
    if arm is not None:
        read = read_hand_path(p, arm)
        p = read if config.proprioception == "joints+hand" else read[..., arm.joints :]
    if not moving:
        return p, lengths
    if vision is None:
        raise ValueError("this model's MTRNN_s reads the object's motion: it needs the vision features")
    v, _ = padded(vision, lengths, WITH_CENTROID)
    if v.shape[1] != p.shape[1]:
        raise ValueError(f"proprioception has {p.shape[1]} steps and vision {v.shape[1]}: not one time grid")
    return torch.cat([p, object_motion(v, lengths)], dim=-1), lengths


MOTION_COLUMNS = 2  # the object's motion: its centroid's x, y relative to the first frame's


def object_motion(vision: Tensor, lengths: Tensor) -> Tensor:
    """The object's centroid relative to the first frame's, [B, T, 2] (0 after each sequence's end),
    from padded vision features with the centroid (`model.encoding.vision`): its own motion."""
    centroid = vision[..., VISUAL_FEATURES : VISUAL_FEATURES + 2]
    valid = (torch.arange(vision.shape[1])[None, :] < lengths[:, None])[..., None]
    return (centroid - centroid[:, :1]) * valid


def visual_inputs(
    vision: Sequence[np.ndarray] | Tensor, config: MultiMTRNNConfig, lengths: Tensor | None = None
) -> tuple[Tensor, Tensor]:
    """What MTRNN_v reads, padded [B, T, io], and the lengths [B], from a list of [T_i, F] vision
    features (`model.encoding.vision`) or a padded [B, T, F] tensor with lengths: the first
    `config.visual.io` (the paper's 19, or with the object's centroid); with `config.object_motion`
    = "visual" the centroid relative to the first frame's instead (`object_motion`)."""
    v, lengths = padded(vision, lengths, config.visual.io)
    if config.object_motion != "visual":
        return v, lengths
    return torch.cat([v[..., :VISUAL_FEATURES], object_motion(v, lengths)], dim=-1), lengths


@dataclass
class Description:
    """What the model says about one scene, and the Csc states on the way."""

    text: str
    words: list[str]
    phonemes: list[str]
    activity: np.ndarray  # [T_a, |B|] softmax IO activity of MTRNN_a
    csc_s: np.ndarray | None  # [csc_s] c_s,T (None when generated from a given c_a,0)
    csc_v: np.ndarray | None  # [csc_v] c_v,T
    csc_a: np.ndarray  # [csc_a] c_a,0


CSC_SPACES = ("somatosensory", "visual", "auditory")  # c_s,T, c_v,T, c_a,0 (Fig. 10)


def csc_vectors(descriptions: Sequence[Description]) -> dict[str, np.ndarray]:
    """Per space, the Csc vectors of the described scenes stacked [scenes, csc]: c_s,T, c_v,T and
    the c_a,0 the assemblies produced."""
    return {
        "somatosensory": np.stack([d.csc_s for d in descriptions]),
        "visual": np.stack([d.csc_v for d in descriptions]),
        "auditory": np.stack([d.csc_a for d in descriptions]),
    }


@dataclass
class NetTrace:
    """One MTRNN's activity over time: activations y per layer and the Csc internal states z."""

    io: np.ndarray  # [T, |IO|]
    cf: np.ndarray  # [T, |Cf|]
    cs: np.ndarray  # [T, |Cs|]
    csc: np.ndarray  # [T, |Csc|] internal states z of the Csc units


@dataclass
class ActivityTrace:
    """All three nets' activity for one scene (teaching pages): perception in, utterance out."""

    somatosensory: NetTrace
    visual: NetTrace
    auditory: NetTrace
    description: Description


@dataclass
class Timeline:
    """What the model would say if asked at every step t of one recording (read up to t).

    Entry t is the utterance generated from c_a,0(t), the assemblies' answer to the Csc states
    z of MTRNN_s and MTRNN_v at step t; the last entry is `MultiMTRNN.describe`'s answer. A word
    *settles* at the step from which it stays: one past the last step at which it was otherwise.
    """

    texts: list[str]  # [T] the utterance at each step
    words: list[list[str]]  # [T] its words
    csc_a: np.ndarray  # [T, csc_a] c_a,0(t)
    word_settles: list[int]  # per word of the last utterance, the step from which it is said
    slots: list[list[str]]  # the phrases of each slot (word units); empty for the paper's CAs
    slot_probabilities: list[np.ndarray]  # per slot [T, phrases]: the word units' p at t
    slot_settles: list[int]  # per slot, the step from which its most probable phrase stays


def settle_step(holds: Sequence[bool] | np.ndarray) -> int:
    """The step from which `holds` is true to the end: one past the last step at which it was
    false (0 when it always held, len(holds) when it does not hold at the end)."""
    false = np.flatnonzero(~np.asarray(holds, dtype=bool))
    return int(false[-1]) + 1 if len(false) else 0


def word_settles(words: Sequence[Sequence[str]]) -> list[int]:
    """Per word of the last entry of `words` ([T] word lists), the step from which it is said:
    word j is said at t when the edit alignment of words[t] to the last words matches it."""
    final = list(words[-1])
    said = np.zeros((len(words), len(final)), dtype=bool)
    for t, w in enumerate(words):
        for op, _, j in align(list(w), final).pairs:
            if op == "match":
                said[t, j] = True
    return [settle_step(said[:, j]) for j in range(len(final))]


def _net_trace(net: MTRNN, states: Tensor) -> NetTrace:
    """states: internal states z [T, N] of one sequence."""
    c = net.cfg
    y = net.activation(states).detach().numpy()
    z = states.detach().numpy()
    return NetTrace(
        io=y[:, : c.io],
        cf=y[:, c.io : c.io + c.cf],
        cs=y[:, c.io + c.cf :],
        csc=z[:, net.csc_slice],
    )


def pad_sequences(
    sequences: Sequence[np.ndarray | Tensor], columns: int | None = None
) -> tuple[Tensor, Tensor]:
    """Variable-length [T_i, F] arrays -> zero-padded float32 [B, T_max, F] and lengths [B].

    `columns` keeps the first columns only (e.g. the 19 paper features of 21-column vision)."""
    if len(sequences) == 0:
        raise ValueError("need at least one sequence")
    arrays = [torch.as_tensor(np.asarray(s), dtype=torch.float32) for s in sequences]
    for a in arrays:
        if a.ndim != 2 or a.shape[0] == 0:
            raise ValueError(f"each sequence must be a non-empty [T, F] array, got shape {tuple(a.shape)}")
    width = arrays[0].shape[1] if columns is None else columns
    for a in arrays:
        if a.shape[1] < width:
            raise ValueError(f"sequence has {a.shape[1]} features, the network reads {width}")
    lengths = torch.tensor([a.shape[0] for a in arrays])
    out = torch.zeros(len(arrays), int(lengths.max()), width)
    for i, a in enumerate(arrays):
        out[i, : a.shape[0]] = a[:, :width]
    return out, lengths


class MultiMTRNN(nn.Module):
    """MTRNN_s + MTRNN_v -> cell assemblies -> MTRNN_a (Fig. 4)."""

    def __init__(
        self,
        config: MultiMTRNNConfig | None = None,
        assemblies: nn.Module | None = None,
        seed: int = 0,
    ) -> None:
        super().__init__()
        self.config = config if config is not None else MultiMTRNNConfig()
        g = torch.Generator().manual_seed(seed)
        self.auditory = MTRNN(self.config.auditory, g)
        self.somatosensory = MTRNN(self.config.somatosensory, g)
        self.visual = MTRNN(self.config.visual, g)
        if assemblies is None:
            assemblies = CellAssemblies(
                self.config.somatosensory.csc,
                self.config.visual.csc,
                self.config.auditory.csc,
                self.config.auditory.weight_init,
                seed=seed,
            )
        self.assemblies = assemblies

    @property
    def assemblies_kind(self) -> str:
        return type(self.assemblies).kind

    def assemblies_spec(self) -> dict:
        """{"kind", "kwargs"}: enough to rebuild the assemblies module (see `model.checkpoint`)."""
        return {"kind": self.assemblies_kind, "kwargs": self.assemblies.init_kwargs()}

    # --- perception -> Csc ----------------------------------------------------------------------

    def abstract(
        self,
        proprioception: Sequence[np.ndarray] | Tensor,
        vision: Sequence[np.ndarray] | Tensor,
        proprioception_lengths: Tensor | None = None,
        vision_lengths: Tensor | None = None,
    ) -> tuple[Tensor, Tensor]:
        """(c_s,T, c_v,T) [B, csc] from lists of [T_i, F] arrays, or padded [B, T, F] tensors with
        lengths, as MTRNN_s and MTRNN_v read them (`somatosensory_inputs`, `visual_inputs`)."""
        p, p_len = somatosensory_inputs(proprioception, self.config, proprioception_lengths, vision)
        v, v_len = visual_inputs(vision, self.config, vision_lengths)
        return self.somatosensory.abstract(p, p_len), self.visual.abstract(v, v_len)

    # --- Csc -> utterance -----------------------------------------------------------------------

    def generate(self, c_a0: Tensor, steps: int | None = None) -> Tensor:
        """Closed-loop MTRNN_a activity [B, T_a, |B|] from c_a,0 [B, csc_a] (alpha = 0)."""
        return self.auditory.generate(c_a0, steps or self.config.generation_steps)

    def _description(
        self,
        activity: np.ndarray,
        lexicon: Lexicon,
        c_a: np.ndarray,
        c_s: np.ndarray | None,
        c_v: np.ndarray | None,
    ) -> Description:
        phonemes, words, text = decode_text(activity, lexicon)
        return Description(text, words, phonemes, activity, c_s, c_v, c_a)

    @torch.no_grad()
    def describe_batch(
        self, proprioception: Sequence[np.ndarray], vision: Sequence[np.ndarray], lexicon: Lexicon
    ) -> list[Description]:
        """One `Description` per scene (lists of [T_i, 5] and [T_i, F] arrays)."""
        c_s, c_v = self.abstract(proprioception, vision)
        c_a = self.assemblies(c_s, c_v)
        activity = self.generate(c_a).numpy()
        c_s, c_v, c_a = c_s.numpy(), c_v.numpy(), c_a.numpy()
        return [self._description(activity[i], lexicon, c_a[i], c_s[i], c_v[i]) for i in range(len(activity))]

    def describe(self, proprioception: np.ndarray, vision: np.ndarray, lexicon: Lexicon) -> Description:
        """Proprioception [T, 5] and vision [T, F] of one scene -> what the model says."""
        return self.describe_batch([proprioception], [vision], lexicon)[0]

    @torch.no_grad()
    def generate_from_csc(self, c_a0: np.ndarray | Sequence[float], lexicon: Lexicon) -> Description:
        """Speak from any point of the auditory Csc space (the latent explorer)."""
        c = torch.as_tensor(np.asarray(c_a0), dtype=torch.float32).reshape(1, -1)
        if c.shape[1] != self.config.auditory.csc:
            raise ValueError(f"c_a,0 must have {self.config.auditory.csc} values, got {c.shape[1]}")
        activity = self.generate(c)[0].numpy()
        return self._description(activity, lexicon, c[0].numpy(), None, None)

    def csc_trajectories(self, proprioception: np.ndarray, vision: np.ndarray) -> tuple[Tensor, Tensor]:
        """The Csc internal states z of MTRNN_s and MTRNN_v at every step while they abstract one
        recording, [T, csc] each: row t is the c_T of the recording read up to step t (3.2)."""
        if len(proprioception) != len(vision):
            raise ValueError(
                f"proprioception has {len(proprioception)} steps and vision {len(vision)}: "
                "a timeline needs both on one time grid"
            )
        p, p_len = somatosensory_inputs([proprioception], self.config, vision=[vision])
        v, v_len = visual_inputs([vision], self.config)
        _, s_states = self.somatosensory.abstract(p, p_len, return_states=True)
        _, v_states = self.visual.abstract(v, v_len, return_states=True)
        return s_states[0, :, self.somatosensory.csc_slice], v_states[0, :, self.visual.csc_slice]

    @torch.no_grad()
    def timeline(self, proprioception: np.ndarray, vision: np.ndarray, lexicon: Lexicon) -> Timeline:
        """What the model would say if asked at every step of one recording (see `Timeline`).

        c_s(t), c_v(t) -> assemblies (eq. 17) -> c_a,0(t) for all steps at once; MTRNN_a generates
        from the c_a,0 of every step but the last in one batch; the last step is `describe` itself,
        so the timeline ends exactly on the model's answer.
        """
        c_s, c_v = self.csc_trajectories(proprioception, vision)
        c_a = self.assemblies(c_s, c_v)
        final = self.describe(proprioception, vision, lexicon)
        earlier = self.generate(c_a[:-1]).numpy() if len(c_a) > 1 else np.zeros((0, 1, 1))
        said = [decode_text(a, lexicon) for a in earlier]
        texts = [text for _, _, text in said] + [final.text]
        words = [list(w) for _, w, _ in said] + [list(final.words)]
        csc_a = np.concatenate([c_a[:-1].numpy(), final.csc_a[None]])
        slots: list[list[str]] = []
        probabilities: list[np.ndarray] = []
        if isinstance(self.assemblies, WordAssemblies):
            slots = self.assemblies.slots
            probabilities = [p.numpy() for p in self.assemblies.slot_probabilities(c_s, c_v)]
        slot_settles = [settle_step(p.argmax(axis=1) == p[-1].argmax()) for p in probabilities]
        return Timeline(texts, words, csc_a, word_settles(words), slots, probabilities, slot_settles)

    @torch.no_grad()
    def activity_trace(
        self, proprioception: np.ndarray, vision: np.ndarray, lexicon: Lexicon
    ) -> ActivityTrace:
        """Every layer's activity over time in all three nets for one scene."""
        p, p_len = somatosensory_inputs([proprioception], self.config, vision=[vision])
        v, v_len = visual_inputs([vision], self.config)
        c_s, s_states = self.somatosensory.abstract(p, p_len, return_states=True)
        c_v, v_states = self.visual.abstract(v, v_len, return_states=True)
        c_a = self.assemblies(c_s, c_v)
        activity, a_states = self.auditory.generate(c_a, self.config.generation_steps, return_states=True)
        description = self._description(
            activity[0].numpy(), lexicon, c_a[0].numpy(), c_s[0].numpy(), c_v[0].numpy()
        )
        return ActivityTrace(
            somatosensory=_net_trace(self.somatosensory, s_states[0]),
            visual=_net_trace(self.visual, v_states[0]),
            auditory=_net_trace(self.auditory, a_states[0]),
            description=description,
        )
