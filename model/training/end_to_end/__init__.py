"""Training mode `end_to_end` (the recipe: `mode.py`): the MultiMTRNN learns to describe scenes it
has never seen. `options` names its additions, `words` the heard word slots, `augmentation` what
perception reads, `factors` an object's colour and shape as two things (recoloured recordings, a
factorised MTRNN_v), `generator` stage 1, `perception` stages 2 and 3."""

from model.training.end_to_end.augmentation import InputNormaliser, PerceptionBatch, csc_at, reading_points
from model.training.end_to_end.generator import combinations_said, train_auditory_stage, train_generator
from model.training.end_to_end.mode import train_end_to_end, word_assemblies
from model.training.end_to_end.options import EndToEndOptions
from model.training.end_to_end.perception import (
    calibrate,
    perception_logits,
    recombination_loss,
    selection_split,
    train_joint_stage,
    train_perception_stage,
)
from model.training.end_to_end.words import WordSlots

__all__ = [
    "EndToEndOptions",
    "InputNormaliser",
    "PerceptionBatch",
    "WordSlots",
    "calibrate",
    "combinations_said",
    "csc_at",
    "perception_logits",
    "reading_points",
    "recombination_loss",
    "selection_split",
    "train_auditory_stage",
    "train_end_to_end",
    "train_generator",
    "train_joint_stage",
    "train_perception_stage",
    "word_assemblies",
]
