"""The scenario's physical world, one source for the renderer, the motions, the 3D viewer and the API.

Torso frame of the NAO (metres, x forward, y left, z up). The table top lies `TABLE_Z` below the
torso origin (0.17 m below the right shoulder); the objects stand around `OBJECT_HOME`. The model's
time step is `FPS` (paper 4.1: 20 frames per second): every recording is resampled to it.
"""

from __future__ import annotations

import colorsys

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
