"""The scenario's physical world, one source for the renderer, the motions, the 3D viewer and the API.

Torso frame of the NAO (metres, x forward, y left, z up). The table top lies `TABLE_Z` below the
torso origin (0.17 m below the right shoulder); the objects stand around `OBJECT_HOME`. The model's
time step is `FPS` (paper 4.1: 20 frames per second): every recording is resampled to it.

`World` is one recording's table and object: the paper's (`PAPER_WORLD`, the constants above) or one
drawn by the wide variety (`data.variety`): another table height, placement, size and object form.
"""

from __future__ import annotations

import colorsys
from dataclasses import asdict, dataclass

import numpy as np

FPS = 20.0  # the model's time step, frames per second (paper 4.1)

TABLE_Z = -0.07  # table top, torso frame (0.17 m below the shoulder)
OBJECT_HOME = np.array([0.114, -0.10])  # nominal object position on the table (x, y)
OBJECT_HOME.setflags(write=False)

# Object footprint and height, metres: (half extent along x, half extent along y, height).
# The banana lies across the table (long along y), the phone lengthwise (long along x).
OBJECT_SIZE: dict[str, tuple[float, float, float]] = {
    "apple": (0.024, 0.024, 0.050),
    "banana": (0.013, 0.048, 0.026),
    "dice": (0.020, 0.020, 0.040),
    "phone": (0.028, 0.017, 0.012),
}

# Hue (degrees) of each colour's reference shade and how far a real object's hue may stray from it.
COLOUR_HUE: dict[str, tuple[float, float]] = {
    "red": (0.0, 7.0),
    "yellow": (52.0, 5.0),
    "green": (125.0, 16.0),
    "blue": (218.0, 13.0),
}
REFERENCE_SATURATION = 0.8  # of an object's reference shade (the renderer varies it per recording)
REFERENCE_VALUE = 0.8


def colour_rgb(colour: str) -> tuple[int, int, int]:
    """The reference shade of an object colour as 8-bit RGB (what the 3D viewer draws)."""
    hue, _ = COLOUR_HUE[colour]
    r, g, b = colorsys.hsv_to_rgb(hue / 360.0, REFERENCE_SATURATION, REFERENCE_VALUE)
    return round(r * 255), round(g * 255), round(b * 255)


PHONE_SCREENS: tuple[str, ...] = (
    "dark",
    "light",
    "none",
)  # the phone's top face: screen lit or not, or its back


@dataclass(frozen=True)
class World:
    """The table and the object of one recording; the defaults are the paper's world."""

    table_z: float = TABLE_Z  # table top, torso frame (m)
    object_home: tuple[float, float] = (0.114, -0.10)  # where the teacher puts the object (x, y)
    size_scale: float = 1.0  # the object's size relative to OBJECT_SIZE (motion and camera)
    phone_thickness: float = OBJECT_SIZE["phone"][2]  # (m), before `size_scale`
    phone_screen: str = "dark"  # one of PHONE_SCREENS
    dice_round: float = 0.0  # corner radius of the dice as a fraction of its half side (0: sharp)
    apple_stem: bool = True  # the apple's stem and leaf

    def size(self, shape: str) -> tuple[float, float, float]:
        """(half extent x, half extent y, height) of `shape` in this world (m)."""
        half_x, half_y, height = OBJECT_SIZE[shape]
        if shape == "phone":
            height = self.phone_thickness
        k = self.size_scale
        return half_x * k, half_y * k, height * k

    def form(self, shape: str, banana_bend: float, dice_pips: int) -> str:
        """The object's shape variant, named for held-out regions (the bend and pips are the camera's)."""
        if shape == "apple":
            return "apple-stem" if self.apple_stem else "apple-no-stem"
        if shape == "banana":
            return "banana-straight" if banana_bend < 0.012 else "banana-curved"
        if shape == "dice":
            return f"dice-{'rounded' if self.dice_round > 0 else 'sharp'}-{'pips' if dice_pips else 'plain'}"
        return f"phone-{self.phone_screen}-{'thin' if self.phone_thickness < 0.011 else 'thick'}"

    def to_dict(self) -> dict[str, object]:
        """JSON-friendly form (for corpus metadata)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, values: dict) -> World:
        """Inverse of `to_dict`."""
        return cls(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in values.items()})


PAPER_WORLD = World()
