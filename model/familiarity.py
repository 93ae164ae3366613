"""How familiar a recording is: its distance to the training recordings, per sense, calibrated.

The model describes what it learned from; a recording unlike every training recording (another
arm posture, a longer teacher, another camera) may get a confident but wrong sentence. This
module says so, from the encoded inputs the model reads (paper 4.1.1): proprioception [T, 5] in
[0, 1] and vision [T, F] (its first `vision_columns`, 19 or 21).

**Descriptors.** Each recording is summarised per sense by a fixed-length vector:

- proprioception, three blocks: *postures* (each joint's 5, 25, 50, 75 and 95 % quantiles over
  time, 25 values), *motion* (each joint's range max - min and the log of its mean absolute change
  per step, 10 values; time-normalised, so a slower teacher shows as a lower speed), *duration*
  (log of the number of steps, 1 value);
- vision, up to three blocks: *shape* (the 16 salient distances' means and standard deviations
  over time, 32 values), *colour* (the means of mean R, G, B over time, 3 values: their variation
  over time follows the segmentation's flicker more than the object, and made our own held-out
  scenes look unfamiliar) and, when the model reads the centroid, *position* (its means and
  standard deviations, 4 values).

Every value is standardised by the training recordings' mean and standard deviation (at least
`SCALE_FLOOR`); the distance of two recordings in one block (an *aspect*: postures, motion,
duration, shape, colour, position) is the root mean square difference of the block's values.

**Calibration.** Per aspect b, each training recording i gets r_ib, its distance to the nearest
training recording *of another scene* (leave-one-scene-out: the scene of a recording id is
`model.data.scene_key`; without ids every recording is its own scene, i.e. plain leave-one-out):
the distance a new scene's recording has to what was learned when it is like the training set.
A recording at distance d_b to the nearest training recording in aspect b gets

    p_b = (1 + #{i : r_ib >= d_b}) / (n + 1)

the fraction of training recordings whose own nearest-neighbour distance is at least as large
(the conformal p-value of the nearest-neighbour distance), and the sense's familiarity is that of
its least familiar aspect, Bonferroni-corrected over its B aspects so that it stays a p-value:

    familiarity = min(1, B * min_b p_b)

A training recording (every d_b = 0) scores 1, as does any recording whose every aspect is nearer
than at least a B-th of the training recordings' own neighbours; a recording of a new scene like those of the
training set scores spread over (0, 1], 0.5-0.75 on average (the correction is conservative);
one farther than every
training recording in some aspect scores at most B / (n + 1), about 0.02 for 128 training
recordings. Each aspect has its own nearest recording, so a new combination of familiar aspects
(a colour seen on another object, an action seen with another object) is not unfamiliar.

**Warnings** (`Familiarity.warnings`), plain sentences, each with its threshold:

- an aspect (postures, motion, shape, colour, position) whose distance d_b exceeds `FAR_RATIO`
  times the largest calibration distance max_i r_ib of that aspect: "far outside";
- more than `LENGTH_RATIO` times longer than the longest training recording, or shorter than the
  shortest by that ratio (with both durations in seconds when `fps` is given);
- joints at a limit of their range (encoded within `LIMIT_MARGIN` of 0 or 1, where the encoder
  clips) in at least `LIMIT_STEPS` of the steps, and more often than in any training recording;
- the object not found in at least `MISSING_FRAMES` of the frames, and more often than in any
  training recording (when the training recordings' fractions were given).

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> prop = [np.clip(0.5 + 0.1 * rng.standard_normal((60, 5)), 0, 1) for _ in range(8)]
    >>> vis = [0.5 + 0.05 * rng.standard_normal((60, 19)) for _ in range(8)]
    >>> fam = Familiarity.fit(prop, vis)
    >>> fam.score(prop[0], vis[0])
    {'proprioception': 1.0, 'vision': 1.0}
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from model.data import scene_key
from model.encoding.proprioception import JOINTS

QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)  # the posture block: each joint's quantiles over time
SCALE_FLOOR = 1e-3  # smallest standard deviation a descriptor value is divided by
SPEED_FLOOR = 1e-5  # mean absolute change per step below this counts as this (log of the speed)
FAR_RATIO = 1.5  # a block this many times farther than any calibration distance is "far outside"
LENGTH_RATIO = 1.5  # this many times longer (shorter) than any training recording: "much longer"
LIMIT_MARGIN = 0.005  # encoded joint value within this of 0 or 1: at its limit (clipped)
LIMIT_STEPS = 0.1  # fraction of steps with a joint at its limit that earns a warning
MISSING_FRAMES = 0.1  # fraction of frames without the object that earns a warning

SALIENT = 16  # vision columns 0-15: the salient distances; 16-18 mean R, G, B; 19-20 the centroid
PROPRIOCEPTION_BLOCKS = ("postures", "motion", "duration")
VISION_BLOCKS = ("shape", "colour", "position")
BLOCK_WARNINGS = {  # the duration has its own sentence, with both lengths (`_length_warnings`)
    "postures": "the arm's postures are far outside what the model learned from",
    "motion": "the arm moves unlike anything the model learned from (range or speed of the joints)",
    "shape": "the object's outline is unlike every shape the model learned from",
    "colour": "the object's colour is unlike every colour the model learned from",
    "position": "the object is where the camera never saw one in the recordings the model learned from",
}


def vision_columns(meta: dict) -> int | None:
    """The number of vision columns a checkpoint's model reads (its meta), None if it does not say."""
    if "peer_config" in meta:
        return int(meta["peer_config"].get("vision", 19))
    io = (meta.get("config") or {}).get("visual", {}).get("io")
    return None if io is None else int(io)


def _proprioception_blocks(prop: np.ndarray) -> list[np.ndarray]:
    """Postures, motion and duration of one recording's proprioception [T, 5]."""
    postures = np.quantile(prop, QUANTILES, axis=0).ravel()
    speed = np.abs(np.diff(prop, axis=0)).mean(axis=0) if len(prop) > 1 else np.zeros(prop.shape[1])
    motion = np.concatenate([np.ptp(prop, axis=0), np.log(np.maximum(speed, SPEED_FLOOR))])
    return [postures, motion, np.array([np.log(len(prop))])]


def _vision_blocks(vis: np.ndarray) -> list[np.ndarray]:
    """Shape, colour and (with 21 columns) position of one recording's vision [T, F]."""
    shape, colour, position = vis[:, :SALIENT], vis[:, SALIENT : SALIENT + 3], vis[:, SALIENT + 3 :]
    blocks = [np.concatenate([shape.mean(axis=0), shape.std(axis=0)]), colour.mean(axis=0)]
    if position.shape[1]:
        blocks.append(np.concatenate([position.mean(axis=0), position.std(axis=0)]))
    return blocks


def _limit_fraction(prop: np.ndarray) -> float:
    """Fraction of steps in which some joint sits at a limit of its range."""
    at_limit = (prop <= LIMIT_MARGIN) | (prop >= 1.0 - LIMIT_MARGIN)
    return float(at_limit.any(axis=1).mean())


def _check(array: np.ndarray, what: str, columns: int) -> np.ndarray:
    a = np.asarray(array, dtype=np.float64)
    if a.ndim != 2 or a.shape[0] == 0 or a.shape[1] < columns:
        raise ValueError(f"{what} must be a non-empty [T, >={columns}] array, got shape {a.shape}")
    if not np.all(np.isfinite(a[:, :columns])):
        raise ValueError(f"{what} contains NaN or infinite values")
    return a[:, :columns]


@dataclass(frozen=True)
class Sense:
    """One sense's learned state: standardisation, the training descriptors and the calibration."""

    names: tuple[str, ...]  # its aspects: the blocks of the descriptor
    sizes: tuple[int, ...]  # length of each block
    mean: np.ndarray  # [D]
    scale: np.ndarray  # [D]
    train: np.ndarray  # [n, D] standardised training descriptors
    calibration: np.ndarray  # [n, B] r_ib: leave-one-scene-out nearest-neighbour distance per aspect

    @classmethod
    def fit(cls, names: tuple[str, ...], blocks: list[list[np.ndarray]], groups: np.ndarray) -> Sense:
        sizes = tuple(len(b) for b in blocks[0])
        raw = np.array([np.concatenate(b) for b in blocks])
        mean, scale = raw.mean(axis=0), np.maximum(raw.std(axis=0), SCALE_FLOOR)
        train = (raw - mean) / scale
        distances = _block_distances(train[:, None, :], train[None, :, :], sizes)  # [n, n, B]
        other = groups[:, None] != groups[None, :]
        alone = ~other.any(axis=1)  # a scene that is the whole set: its other recordings count
        other[alone] = ~np.eye(len(train), dtype=bool)[alone]
        calibration = np.where(other[..., None], distances, np.inf).min(axis=1)
        return cls(names[: len(sizes)], sizes, mean, scale, train, calibration)

    def distances(self, blocks: list[np.ndarray]) -> np.ndarray:
        """d_b: the distance to the nearest training recording in each aspect [B]."""
        z = (np.concatenate(blocks) - self.mean) / self.scale
        return _block_distances(z[None, :], self.train, self.sizes).min(axis=0)

    def familiarity(self, distances: np.ndarray) -> float:
        """min(1, B * min_b p_b): see the module's calibration."""
        n, aspects = self.calibration.shape
        p = (1 + np.count_nonzero(self.calibration >= distances[None, :], axis=0)) / (n + 1)
        return float(min(1.0, aspects * p.min()))

    def far(self, distances: np.ndarray) -> list[str]:
        """The aspects farther than `FAR_RATIO` times their largest calibration distance."""
        far = distances > FAR_RATIO * self.calibration.max(axis=0)
        return [name for name, is_far in zip(self.names, far, strict=True) if is_far]

    def arrays(self, prefix: str) -> dict[str, np.ndarray]:
        values = {
            "sizes": np.array(self.sizes, dtype=np.int64),
            "mean": self.mean,
            "scale": self.scale,
            "train": self.train,
            "calibration": self.calibration,
        }
        return {f"{prefix}.{k}": np.ascontiguousarray(v) for k, v in values.items()}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], prefix: str, names: tuple[str, ...]) -> Sense:
        a = {k: arrays[f"{prefix}.{k}"] for k in ("sizes", "mean", "scale", "train", "calibration")}
        sizes = tuple(int(s) for s in a.pop("sizes"))
        return cls(names[: len(sizes)], sizes, **a)


def _block_distances(a: np.ndarray, b: np.ndarray, sizes: tuple[int, ...]) -> np.ndarray:
    """Root mean square difference per block of the last axis (broadcast over the leading axes)."""
    squared = (a - b) ** 2
    edges = np.cumsum((0, *sizes))
    blocks = [squared[..., s:e].mean(axis=-1) for s, e in zip(edges[:-1], edges[1:], strict=True)]
    return np.sqrt(np.stack(blocks, axis=-1))


@dataclass(frozen=True)
class Assessment:
    """What familiarity says about one recording."""

    familiarity: dict[str, float]  # "proprioception", "vision": in [0, 1]
    warnings: list[str]


@dataclass(frozen=True)
class Familiarity:
    """How far a recording lies from the training recordings, per sense (see the module docstring).
    Learned state ends in `_`; `fit` builds it, `score` and `warnings` are pure."""

    proprioception_: Sense
    vision_: Sense
    vision_columns_: int
    steps_: tuple[int, int]  # shortest and longest training recording, in steps
    limit_fraction_: float  # largest fraction of steps at a joint limit among the training recordings
    missing_: float | None  # largest fraction of frames without the object, None when not known

    @classmethod
    def fit(
        cls,
        proprioception: Sequence[np.ndarray],
        vision: Sequence[np.ndarray],
        found: Sequence[float] | None = None,
        ids: Sequence[str] | None = None,
        vision_columns: int | None = None,
    ) -> Familiarity:
        """Fit on the training recordings' encodings; `found`: each one's fraction of frames with the
        object; `ids`: recording ids (calibration leaves out each recording's scene); `vision_columns`:
        the vision columns the model reads (default: all of them)."""
        if len(proprioception) < 2 or len(vision) != len(proprioception):
            raise ValueError("familiarity needs at least two training recordings, with both senses each")
        columns = vision_columns or min(np.shape(v)[1] for v in vision)
        prop = [_check(p, "proprioception", JOINTS) for p in proprioception]
        vis = [_check(v, "vision", columns) for v in vision]
        groups = np.array(
            [scene_key(i) for i in ids] if ids is not None else [str(i) for i in range(len(prop))]
        )
        lengths = [len(p) for p in prop]
        return cls(
            proprioception_=Sense.fit(
                PROPRIOCEPTION_BLOCKS, [_proprioception_blocks(p) for p in prop], groups
            ),
            vision_=Sense.fit(VISION_BLOCKS, [_vision_blocks(v) for v in vis], groups),
            vision_columns_=int(columns),
            steps_=(min(lengths), max(lengths)),
            limit_fraction_=max(_limit_fraction(p) for p in prop),
            missing_=None if found is None else float(1.0 - min(found)),
        )

    def assess(
        self,
        proprioception: np.ndarray,
        vision: np.ndarray,
        found: float | None = None,
        fps: float | None = None,
    ) -> Assessment:
        """`score` and `warnings` of one recording, its descriptors computed once (what the server
        calls); `found`: its fraction of frames with the object; `fps`: steps per second."""
        prop = _check(proprioception, "proprioception", JOINTS)
        vis = _check(vision, "vision", self.vision_columns_)
        d_s = self.proprioception_.distances(_proprioception_blocks(prop))
        d_v = self.vision_.distances(_vision_blocks(vis))
        scores = {
            "proprioception": round(self.proprioception_.familiarity(d_s), 4),
            "vision": round(self.vision_.familiarity(d_v), 4),
        }
        far = self.proprioception_.far(d_s) + self.vision_.far(d_v)
        out = [BLOCK_WARNINGS[b] for b in far if b in BLOCK_WARNINGS]
        out += self._length_warnings(len(prop), fps)
        at_limit = _limit_fraction(prop)
        if at_limit >= LIMIT_STEPS and at_limit > self.limit_fraction_:
            out.append(f"the joint angles sit at their limits in {100 * at_limit:.0f} % of the steps")
        missing = None if found is None else 1.0 - float(found)
        if missing is not None and missing >= MISSING_FRAMES and missing > (self.missing_ or 0.0):
            out.append(f"no object found in {100 * missing:.0f} % of the frames")
        return Assessment(scores, out)

    def score(self, proprioception: np.ndarray, vision: np.ndarray) -> dict[str, float]:
        """Familiarity in [0, 1] per sense: 1 like a training recording, ~0 far outside all of them."""
        return self.assess(proprioception, vision).familiarity

    def warnings(
        self,
        proprioception: np.ndarray,
        vision: np.ndarray,
        found: float | None = None,
        fps: float | None = None,
    ) -> list[str]:
        """Plain sentences on how the recording is unlike the training recordings (thresholds in the
        module docstring)."""
        return self.assess(proprioception, vision, found, fps).warnings

    def _length_warnings(self, steps: int, fps: float | None) -> list[str]:
        def length(n: int) -> str:
            return f"{n / fps:.1f} s" if fps else f"{n} steps"

        shortest, longest = self.steps_
        if steps > LENGTH_RATIO * longest:
            return [
                f"the recording is much longer than any the model learned from "
                f"({length(steps)} against at most {length(longest)})"
            ]
        if steps * LENGTH_RATIO < shortest:
            return [
                f"the recording is much shorter than any the model learned from "
                f"({length(steps)} against at least {length(shortest)})"
            ]
        return []

    def arrays(self) -> dict[str, np.ndarray]:
        """Every learned value as named arrays (what `model.checkpoint` saves as safetensors)."""
        scalars = [
            self.vision_columns_,
            *self.steps_,
            self.limit_fraction_,
            np.nan if self.missing_ is None else self.missing_,
        ]
        return {
            **self.proprioception_.arrays("proprioception"),
            **self.vision_.arrays("vision"),
            "scalars": np.array(scalars, dtype=np.float64),
        }

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> Familiarity:
        columns, shortest, longest, limit, missing = (float(x) for x in arrays["scalars"])
        return cls(
            proprioception_=Sense.from_arrays(arrays, "proprioception", PROPRIOCEPTION_BLOCKS),
            vision_=Sense.from_arrays(arrays, "vision", VISION_BLOCKS),
            vision_columns_=int(columns),
            steps_=(int(shortest), int(longest)),
            limit_fraction_=limit,
            missing_=None if np.isnan(missing) else missing,
        )
