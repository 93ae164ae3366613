"""The scenario of the paper (4.1, Fig. 5): grammar, the 64 scenes and readable recording ids.

    S   -> ACT the COL OBJ.
    ACT -> pull | push | show me | slide
    COL -> blue | green | red | yellow
    OBJ -> apple | banana | dice | phone

Every scene was recorded four times (variants 0..3), by different teachers; the wide corpus
(`data.variety`) records each up to 16 times (variants 0..15).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from itertools import product

ACTIONS: tuple[str, ...] = ("pull", "push", "show me", "slide")
COLOURS: tuple[str, ...] = ("blue", "green", "red", "yellow")
SHAPES: tuple[str, ...] = ("apple", "banana", "dice", "phone")
VARIANTS: tuple[int, ...] = tuple(range(16))  # recordings of a scene: the paper's corpus has 0..3

# Fig. 5b: the instructions the human teachers were given.
TEACHING_INSTRUCTIONS: dict[str, str] = {
    "pull": "move the arm behind the object and drag it towards the torso",
    "push": "move the arm in front of the object and push it away from the torso",
    "show me": "point with the hand to the object",
    "slide": "move the arm to the right of the object and slide it horizontally to the left",
}


@dataclass(frozen=True, order=True)
class Scene:
    """One of the 64 interactions: an action on an object of one colour and one shape."""

    action: str
    colour: str
    shape: str

    def __post_init__(self) -> None:
        if self.action not in ACTIONS:
            raise ValueError(f"unknown action {self.action!r}; expected one of {ACTIONS}")
        if self.colour not in COLOURS:
            raise ValueError(f"unknown colour {self.colour!r}; expected one of {COLOURS}")
        if self.shape not in SHAPES:
            raise ValueError(f"unknown shape {self.shape!r}; expected one of {SHAPES}")

    @property
    def id(self) -> str:
        """URL-friendly id, e.g. ``show-me-red-apple``."""
        return f"{self.action.replace(' ', '-')}-{self.colour}-{self.shape}"

    @property
    def utterance(self) -> str:
        """The one sentence of the grammar that describes the scene (Fig. 5c)."""
        return f"{self.action} the {self.colour} {self.shape}."

    @property
    def index(self) -> int:
        """Position in `all_scenes()`: action-major, then colour, then shape."""
        return (
            ACTIONS.index(self.action) * len(COLOURS) * len(SHAPES)
            + COLOURS.index(self.colour) * len(SHAPES)
            + SHAPES.index(self.shape)
        )


def all_scenes() -> list[Scene]:
    """The 64 scenes in a fixed order (action-major, then colour, then shape)."""
    return [Scene(a, c, s) for a, c, s in product(ACTIONS, COLOURS, SHAPES)]


def scene_from_utterance(utterance: str) -> Scene:
    """Parse a sentence of the grammar back into its scene (raises ValueError otherwise)."""
    words = utterance.strip().rstrip(".").lower().split()
    if len(words) >= 4 and words[-3] == "the":
        return Scene(" ".join(words[:-3]), words[-2], words[-1])
    raise ValueError(f"{utterance!r} is not a sentence of the grammar 'ACT the COL OBJ.'")


def recording_id(scene: Scene, variant: int) -> str:
    """Readable id of one recording, e.g. ``slide-red-apple-2``."""
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS[0]}..{VARIANTS[-1]}, got {variant}")
    return f"{scene.id}-{variant}"


def parse_recording_id(rid: str) -> tuple[Scene, int]:
    """Inverse of `recording_id`; raises ValueError naming what is wrong."""
    parts = rid.split("-")
    if len(parts) < 4 or not re.fullmatch(r"0|[1-9][0-9]*", parts[-1]):
        raise ValueError(f"{rid!r} is not a recording id like 'slide-red-apple-2'")
    action = " ".join(parts[:-3])
    scene = Scene(action, parts[-3], parts[-2])
    variant = int(parts[-1]) if len(parts[-1]) <= 2 else -1
    if variant not in VARIANTS:
        raise ValueError(f"{rid!r}: variant must be one of {VARIANTS[0]}..{VARIANTS[-1]}")
    return scene, variant
