"""The NAO's bottom head camera and everything random about a recording's look (`Appearance`).

`Appearance.sample` draws camera pose and field of view, light, table, object shade and proportions,
noise and blur from a seed; `Camera` is the pinhole camera an appearance (plus head jitter) gives,
with the homography that maps the table texture into the image. `project` and `head_angles` are the
public geometry: torso-frame points to pixels, and the head angles that aim the camera at a point.
"""

from __future__ import annotations

import colorsys
from dataclasses import asdict, dataclass

import numpy as np

from data.world import COLOUR_HUE, TABLE_Z

WIDTH, HEIGHT = 320, 240
NAO_HFOV = float(np.deg2rad(60.97))  # NAO V5 camera horizontal field of view
HEAD_ORIGIN = np.array([0.0, 0.0, 0.1265])  # HeadYaw/HeadPitch joint in the torso frame
BOTTOM_CAMERA_OFFSET = np.array([0.05071, 0.0, 0.01774])  # CameraBottom in the head frame
BOTTOM_CAMERA_PITCH = 0.6929  # CameraBottom looks 39.7 degrees down in the head frame
HEAD_PITCH_LIMITS = (-0.6720, 0.5149)

TABLE_KINDS: tuple[str, ...] = ("wood", "plain", "cloth")

TEX_SIZE = 384
TEX_X = (-0.05, 0.55)  # torso-frame x range covered by the table texture (m)
TEX_Y = (-0.45, 0.25)  # torso-frame y range
_OPTICAL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])  # body (x fwd) -> optical
NEAR = 0.03  # near clipping distance (m)


def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def hsv_to_rgb(h_deg: float, s: float, v: float) -> np.ndarray:
    return np.array(colorsys.hsv_to_rgb((h_deg % 360.0) / 360.0, s, v)) * 255.0


@dataclass(frozen=True)
class Appearance:
    """Everything about how a recording looks, apart from the scene and the motion."""

    hfov: float  # horizontal field of view (rad)
    head_yaw: float  # (rad) the camera turns with the head
    head_pitch: float  # (rad) positive looks down
    camera_roll: float  # (rad) mounting / simulator difference
    camera_offset: tuple[float, float, float]  # camera displacement from the NAO's (m)
    shake: float  # per-frame camera jitter (rad, std)
    light_direction: tuple[float, float, float]  # unit vector towards the light
    light_intensity: float  # directional light
    ambient: float  # ambient light
    exposure: float  # overall brightness factor
    light_gradient: tuple[float, float]  # brightness slope across the image (x, y)
    vignetting: float
    white_balance: tuple[float, float, float]  # per-channel gains (R, G, B)
    noise_sigma: float  # sensor noise (grey levels)
    blur_sigma: float  # optical / motion blur (pixels)
    table_kind: str  # wood, plain or cloth
    table_hsv: tuple[float, float, float]  # hue (deg), saturation, value
    table_edge: float  # torso-frame x of the table's far edge (m)
    background_hsv: tuple[float, float, float]  # beyond the table
    shadow_strength: float
    object_hue_shift: float  # in [-1, 1], scaled by the colour's hue tolerance
    object_saturation: float
    object_value: float
    specular: float
    object_scale: float  # shape proportions vary a little between object sets
    banana_bend: float  # (m) how far the banana's middle bulges
    dice_pips: int  # pips on the dice's top face (0: a plain dice, no pips at all)
    seed: int  # texture and noise
    width: int = WIDTH
    height: int = HEIGHT

    @classmethod
    def sample(cls, rng: np.random.Generator, width: int = WIDTH, height: int = HEIGHT) -> Appearance:
        """A new, widely varied appearance. The camera is aimed near the workspace in front of the arm."""
        hfov = float(np.deg2rad(rng.uniform(52.0, 70.0)))
        offset = tuple(float(v) for v in rng.uniform([-0.02, -0.02, -0.015], [0.02, 0.02, 0.03]))
        aim = np.array([0.13 + rng.uniform(-0.02, 0.02), -0.105 + rng.uniform(-0.025, 0.025), TABLE_Z])
        yaw, pitch = head_angles(aim, offset)  # type: ignore[arg-type]
        elevation = rng.uniform(np.deg2rad(35.0), np.deg2rad(85.0))
        azimuth = rng.uniform(-np.pi, np.pi)
        light = (
            float(np.cos(elevation) * np.cos(azimuth)),
            float(np.cos(elevation) * np.sin(azimuth)),
            float(np.sin(elevation)),
        )
        kind = str(rng.choice(TABLE_KINDS))
        if kind == "wood":
            table = (rng.uniform(15.0, 40.0), rng.uniform(0.2, 0.45), rng.uniform(0.35, 0.85))
        elif kind == "plain":
            table = (rng.uniform(0.0, 360.0), rng.uniform(0.0, 0.18), rng.uniform(0.25, 0.95))
        else:
            table = (rng.uniform(0.0, 360.0), rng.uniform(0.05, 0.3), rng.uniform(0.3, 0.85))
        return cls(
            hfov=hfov,
            head_yaw=yaw,
            head_pitch=pitch,
            camera_roll=float(rng.normal(0.0, 0.04)),
            camera_offset=offset,  # type: ignore[arg-type]
            shake=float(rng.uniform(0.0, 0.003)),
            light_direction=light,
            light_intensity=float(rng.uniform(0.45, 0.85)),
            ambient=float(rng.uniform(0.3, 0.55)),
            exposure=float(rng.uniform(0.75, 1.2)),
            light_gradient=(float(rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.3, 0.3))),
            vignetting=float(rng.uniform(0.0, 0.35)),
            white_balance=tuple(float(v) for v in rng.uniform(0.86, 1.14, 3)),  # type: ignore[arg-type]
            noise_sigma=float(rng.uniform(1.0, 7.0)),
            blur_sigma=float(rng.uniform(0.0, 1.3)),
            table_kind=kind,
            table_hsv=tuple(float(v) for v in table),  # type: ignore[arg-type]
            table_edge=float(rng.uniform(0.25, 0.6)),
            background_hsv=tuple(float(v) for v in rng.uniform([0.0, 0.0, 0.1], [360.0, 0.25, 0.8])),  # type: ignore[arg-type]
            shadow_strength=float(rng.uniform(0.2, 0.55)),
            object_hue_shift=float(rng.uniform(-1.0, 1.0)),
            object_saturation=float(rng.uniform(0.62, 0.95)),
            object_value=float(rng.uniform(0.6, 0.95)),
            specular=float(rng.uniform(0.0, 0.6)),
            object_scale=float(rng.uniform(0.9, 1.1)),
            banana_bend=float(rng.uniform(0.016, 0.03)),
            dice_pips=int(rng.integers(1, 7)),
            seed=int(rng.integers(0, 2**31 - 1)),
            width=width,
            height=height,
        )

    def to_dict(self) -> dict[str, object]:
        """JSON-friendly form (for corpus metadata)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, values: dict) -> Appearance:
        """Inverse of `to_dict`."""
        return cls(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in values.items()})

    def object_rgb(self, colour: str) -> np.ndarray:
        """The object's lit RGB (0-255 float) for one of the four colours, in this appearance's shade."""
        hue, tolerance = COLOUR_HUE[colour]
        value = max(self.object_value, 0.8) if colour == "yellow" else self.object_value
        return hsv_to_rgb(hue + self.object_hue_shift * tolerance, self.object_saturation, value)


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: pose in the torso frame, focal length and principal point (pixels)."""

    rotation: np.ndarray  # world -> optical frame
    translation: np.ndarray
    position: np.ndarray  # in the torso frame
    focal: float
    centre: tuple[float, float]

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        return points @ self.rotation.T + self.translation

    def project(self, points: np.ndarray) -> np.ndarray:
        """[n,3] torso-frame points (in front of the camera) -> [n,2] pixel coordinates."""
        pc = self.to_camera(points)
        z = np.maximum(pc[:, 2], NEAR)
        u = self.focal * pc[:, 0] / z + self.centre[0]
        return np.stack([u, self.focal * pc[:, 1] / z + self.centre[1]], 1)

    def depth(self, points: np.ndarray) -> np.ndarray:
        return self.to_camera(np.atleast_2d(points))[:, 2]

    def table_homography(self, table_z: float) -> np.ndarray:
        """Texel (col, row) of the table texture (the table top at height `table_z`) -> pixel."""
        dx = (TEX_X[1] - TEX_X[0]) / TEX_SIZE
        dy = (TEX_Y[1] - TEX_Y[0]) / TEX_SIZE
        texel_to_world = np.array([[0.0, dx, TEX_X[0]], [dy, 0.0, TEX_Y[0]], [0.0, 0.0, table_z]])
        k = np.array([[self.focal, 0.0, self.centre[0]], [0.0, self.focal, self.centre[1]], [0.0, 0.0, 1.0]])
        return k @ (self.rotation @ texel_to_world + np.outer(self.translation, [0.0, 0.0, 1.0]))


def camera_of(app: Appearance, d_yaw: float = 0.0, d_pitch: float = 0.0) -> Camera:
    """The camera `app` describes, with the head turned by (`d_yaw`, `d_pitch`) rad of jitter."""
    head = rot_z(app.head_yaw + d_yaw) @ rot_y(app.head_pitch + d_pitch)
    position = HEAD_ORIGIN + np.asarray(app.camera_offset) + head @ BOTTOM_CAMERA_OFFSET
    body = head @ rot_y(BOTTOM_CAMERA_PITCH) @ rot_x(app.camera_roll)
    rotation = _OPTICAL @ body.T
    focal = 0.5 * app.width / np.tan(0.5 * app.hfov)
    centre = (0.5 * app.width, 0.5 * app.height)
    return Camera(rotation, -rotation @ position, position, float(focal), centre)


def head_angles(aim: np.ndarray, camera_offset: tuple[float, float, float]) -> tuple[float, float]:
    """Head yaw and pitch (rad, pitch within the NAO's limits) that point the bottom camera,
    displaced by `camera_offset` (m), at the torso-frame point `aim`: for appearances posed beyond
    `Appearance.sample` (e.g. another robot's camera height) that still look at the workspace."""
    yaw, pitch = 0.0, 0.3
    base = HEAD_ORIGIN + np.asarray(camera_offset)
    for _ in range(3):  # the camera position depends on the head angles it is solved for
        d = np.asarray(aim, dtype=float) - (base + rot_z(yaw) @ rot_y(pitch) @ BOTTOM_CAMERA_OFFSET)
        yaw = float(np.arctan2(d[1], d[0]))
        pitch = float(np.arctan2(-d[2], np.hypot(d[0], d[1]))) - BOTTOM_CAMERA_PITCH
    return yaw, float(np.clip(pitch, *HEAD_PITCH_LIMITS))


def project(appearance: Appearance, points: np.ndarray) -> np.ndarray:
    """Pixel coordinates [n,2] of torso-frame points [n,3] in this appearance's (unjittered) camera."""
    return camera_of(appearance).project(np.atleast_2d(np.asarray(points, dtype=float)))
