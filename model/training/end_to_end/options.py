"""The named additions of `end_to_end` (`EndToEndOptions`): each a field, stored in the checkpoint
meta under "end_to_end" and measured in docs/experiments/end_to_end.md."""

from __future__ import annotations

from dataclasses import dataclass

from model.config import OBJECT_MOTION_READERS, PROPRIOCEPTION_READINGS


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
    # which net reads the object's own motion (its centroid relative to the first frame's), evidence
    # for the action in any workspace: "none", "visual" (instead of where it lies) or "somatosensory"
    # (beside the arm) (issue 12, docs/experiments/cross_setup.md: held-out setups' actions 0.74 ->
    # 0.87 beside the hand's path; read by MTRNN_v instead, 0.76, and the objects fall 0.87 -> 0.76)
    object_motion: str = "somatosensory"
    # MTRNN_s reads the joint codes ("joints", the paper's), the hand's path in the torso frame beside
    # them ("joints+hand") or instead ("hand"), by the arm's forward kinematics (issue 12,
    # docs/experiments/cross_setup.md: "hand" reads held-out setups' actions at 0.74, the codes 0.54)
    hand_path: str = "hand"
    normalise_inputs: bool = True  # standardise encoder inputs while training (`InputNormaliser`)
    selection_scenes: int = 0  # training scenes held out to calibrate and select perception
    select_every: int = 10  # epochs between two selections
    input_noise: float = 0.0  # std of Gaussian noise on the (normalised) encoder inputs, per epoch
    vision_window: int = 0  # > 0: MTRNN_v learns from a random window of this many frames per epoch
    time_warp: float = 0.0  # > 0: every epoch each recording replays at a random speed in [1 - w, 1 + w]
    recombine: float = 1.0  # weight of the word loss on recombined pairs (`recombination_loss`)
    recombine_pairs: int = 1  # recombined pairings (random permutations) per epoch
    recombine_objects: float = 1.0  # word loss weight on recoloured recordings (`factors`)
    factorised_vision: bool = False  # MTRNN_v: a colour and a shape pathway (`factors`)
    weight_decay: float = 1e-4  # L2 penalty on the encoders' and word units' weight matrices
    average_from: float = 0.5  # > 0: perception weights averaged from this fraction of epochs on
    auditory_epochs: int = 1500  # stage 1, at most, per attempt (docs/experiments/end_to_end.md, rounds 3-4)
    auditory_attempts: int = 3  # MTRNN_a restarts from new weights until it says every word combination
    auditory_check_every: int = 250  # > 0: it checks itself this often and stops once it says them all
    perception_epochs: int = 300  # stage 2 (the held-out selection keeps the best epoch)
    joint_epochs: int = 0  # stage 3

    def __post_init__(self) -> None:
        if self.hand_path not in PROPRIOCEPTION_READINGS:
            raise ValueError(f"hand_path must be one of {PROPRIOCEPTION_READINGS}, got {self.hand_path!r}")
        if self.object_motion not in OBJECT_MOTION_READERS:
            raise ValueError(f"object_motion must be one of {OBJECT_MOTION_READERS}: {self.object_motion!r}")
        if self.object_motion == "visual" and not self.vision_centroid:
            raise ValueError("object_motion 'visual' needs vision_centroid (the motion is the centroid's)")
        if self.average_from > 0 and self.selection_scenes > 0:
            raise ValueError("average_from needs selection_scenes = 0 (the average is the final state)")
        if self.recombine > 0 and not self.slot_softmax:
            raise ValueError("recombine needs slot_softmax word units")
