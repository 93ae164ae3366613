"""Configuration of the MultiMTRNN: every hyper-parameter with the paper's default (Table 1)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from typing import Literal

from model.encoding.vision import FEATURES as WITH_CENTROID  # the paper's 19, then the centroid

# Scaled logistic of the paper (3.4.3, after Heinrich & Wermter 2014), see `model.mtrnn.scaled_logistic`.
KAPPA_H = 0.35795  # range: f spans (-kappa_h, 1 + kappa_h)
KAPPA_W = 0.92  # slope


@dataclass
class MTRNNConfig:
    """One MTRNN: IO, context-fast (Cf) and context-slow (Cs) layers with their timescales (eq. 3)."""

    io: int  # |I_IO|: input (encoders) or output (generator) neurons
    cf: int  # |I_Cf|
    cs: int  # |I_Cs|
    tau_io: float  # timescale of IO
    tau_cf: float  # timescale of Cf
    tau_cs: float  # timescale of Cs
    csc: int = -1  # |I_Csc|; -1 means ceil(|I_Cs| / 2) as in 4.2
    io_activation: Literal["softmax", "logistic"] = "logistic"  # softmax only on MTRNN_a's IO (3.4.3)
    weight_init: float = 0.025  # W^0: weights drawn from U(-0.025, 0.025)
    csc_init: float = 1.0  # C^0: c_0 (generator) from +-0.01, c_T (encoders) from +-1.0

    def __post_init__(self) -> None:
        if self.csc < 0:
            self.csc = math.ceil(self.cs / 2)
        if not 0 < self.csc <= self.cs:
            raise ValueError(f"|Csc| must be in 1..|Cs|={self.cs}, got {self.csc}")

    @property
    def size(self) -> int:
        return self.io + self.cf + self.cs


def auditory_config(io: int | None = None) -> MTRNNConfig:
    """MTRNN_a, the generator with context bias (Table 1).

    Table 1 gives 44 IO neurons for the alphabet B; our B has 43 symbols (see
    `model.encoding.utterance`), so the IO layer is sized len(PHONEMES) unless told otherwise.
    """
    if io is None:
        from model.encoding.utterance import PHONEMES

        io = len(PHONEMES)
    return MTRNNConfig(
        io=io, cf=80, cs=23, tau_io=2, tau_cf=5, tau_cs=70, io_activation="softmax", csc_init=0.01
    )


def somatosensory_config() -> MTRNNConfig:
    """MTRNN_s, proprioception encoder with context abstraction (Table 1)."""
    return MTRNNConfig(io=5, cf=40, cs=23, tau_io=2, tau_cf=5, tau_cs=50)


def visual_config(io: int = 19) -> MTRNNConfig:
    """MTRNN_v, vision encoder with context abstraction (Table 1)."""
    return MTRNNConfig(io=io, cf=40, cs=23, tau_io=2, tau_cf=5, tau_cs=16)


PROPRIOCEPTION_READINGS = ("joints", "joints+hand", "hand")
OBJECT_MOTION_READERS = ("none", "visual", "somatosensory")

# The learning rules (`model.training.common.make_optimiser`): the paper's adaptive rates times
# gradients (eqs. 7-10), sign-based RPROP, Adam.
LEARNING_RULES = ("paper", "rprop", "adam")
# eq. (10)'s open constant: zeta_i = ZETA_GAIN * mean eta_ij, calibrated on Fig. 3 alone
# (docs/experiments/faithful.md, `mtrnn cosine`).
ZETA_GAIN = 30.0


@dataclass
class TrainingConfig:
    """How the nets learn: full-batch BPTT with one of `LEARNING_RULES`."""

    # None: the mode's own rule (faithful and the cosine experiment: "paper"; end_to_end: "rprop").
    optimiser: Literal["paper", "rprop", "adam"] | None = None
    zeta_gain: float = ZETA_GAIN  # eq. (10): zeta = zeta_gain * the mean rate of a Csc unit's weights
    lr: float = 0.05  # eta^0, beta^0, zeta^0: initial rates
    xi_increase: float = 1.01  # xi+
    xi_decrease: float = 0.96  # xi-
    lr_min: float = 1e-6  # eta_min
    lr_max: float = 1.0  # eta_max
    adam_lr: float = 1e-2
    alpha: float = 0.1  # teacher forcing of MTRNN_a (eq. 5)
    psi_s: float = 5e-4  # self-organisation forcing of MTRNN_s (best in 4.3)
    psi_v: float = 5e-5  # self-organisation forcing of MTRNN_v (Table 1)
    epochs_auditory: int = 1500
    epochs_somatosensory: int = 400
    epochs_visual: int = 400
    epochs_assemblies: int = 2000
    progress_every: int = 10  # epochs between two progress reports
    threads: int = 1  # torch.set_num_threads during training (one run per core is fastest)


@dataclass
class MultiMTRNNConfig:
    """The whole architecture of Fig. 4."""

    auditory: MTRNNConfig = field(default_factory=auditory_config)
    somatosensory: MTRNNConfig = field(default_factory=somatosensory_config)
    visual: MTRNNConfig = field(default_factory=visual_config)
    training: TrainingConfig = field(default_factory=TrainingConfig)
    # T_a of closed-loop generation: the longest training utterance's encoding + a margin. Set by
    # training (`model.training.common.generation_steps`); stored here so a checkpoint carries it.
    generation_steps: int = 60
    # Named options of the training mode (fields of model.training.end_to_end.EndToEndOptions or
    # model.training.faithful.FaithfulOptions); empty means the mode's defaults (the paper's, for faithful).
    options: dict = field(default_factory=dict)
    # What MTRNN_s reads (`model.multimtrnn.somatosensory_inputs`, end_to_end's `hand_path`): "joints"
    # (the paper's joint codes), "joints+hand" (and the hand's path beside them) or "hand" (the
    # hand's path instead), the path read through `arm` (`model.encoding.kinematics.ArmChain.to_dict()`).
    proprioception: Literal["joints", "joints+hand", "hand"] = "joints"
    arm: dict | None = None
    # Which net reads the object's own motion, its centroid relative to the first frame's (evidence
    # for the action whatever the workspace; end_to_end's `object_motion`): "none" (MTRNN_v reads
    # where the object lies, if it reads the centroid at all), "visual" (MTRNN_v reads the motion
    # instead, `model.multimtrnn.visual_inputs`) or "somatosensory" (MTRNN_s reads it beside the
    # arm, `somatosensory_inputs`).
    object_motion: Literal["none", "visual", "somatosensory"] = "none"

    def __post_init__(self) -> None:
        if self.proprioception not in PROPRIOCEPTION_READINGS:
            raise ValueError(
                f"proprioception must be one of {PROPRIOCEPTION_READINGS}, got {self.proprioception!r}"
            )
        if self.proprioception != "joints" and self.arm is None:
            raise ValueError(f"reading {self.proprioception!r} needs the arm's kinematics (`arm`)")
        if self.object_motion not in OBJECT_MOTION_READERS:
            raise ValueError(f"object_motion must be one of {OBJECT_MOTION_READERS}: {self.object_motion!r}")
        if self.object_motion == "visual" and self.visual.io != WITH_CENTROID:
            raise ValueError(f"object_motion 'visual' needs MTRNN_v to read {WITH_CENTROID} inputs")

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> MultiMTRNNConfig:
        return cls(
            auditory=MTRNNConfig(**d["auditory"]),
            somatosensory=MTRNNConfig(**d["somatosensory"]),
            visual=MTRNNConfig(**d["visual"]),
            training=TrainingConfig(**d["training"]),
            generation_steps=int(d.get("generation_steps", 60)),
            options=dict(d.get("options") or {}),
            proprioception=d.get("proprioception", "joints"),
            arm=d.get("arm"),
            object_motion=d.get("object_motion", "none"),
        )


def mode_options(options_class: type, config: MultiMTRNNConfig) -> object:
    """`options_class` (a mode's options dataclass) built from `config.options`, named errors."""
    known = {f.name for f in fields(options_class)}
    unknown = sorted(set(config.options) - known)
    if unknown:
        raise ValueError(f"unknown {options_class.__name__} option(s) {unknown}; known: {sorted(known)}")
    return options_class(**config.options)
