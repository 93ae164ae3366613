"""The robot's camera view of the table, rendered per time step with OpenCV drawing.

No 3-D engine: a pinhole camera (the NAO's bottom head camera, `Appearance` moves and varies it)
projects the table plane (a warped texture), the object (a ray-cast sphere for the apple,
extruded outlines for banana, dice and phone, flat-shaded by a directional light, with a soft
shadow) and the arm (capsules and boxes at the forward-kinematics positions, with its shadow).
Then lighting gradient, vignetting, exposure, white balance, blur and sensor noise.

Everything random lives in `Appearance` (drawn from a seed): the corpus varies camera pose and
field of view, light, table (wood grain, plain, cloth; base colour never as saturated as an
object), object shade, shape proportions, noise and blur, so that a model trained on it does not
learn one renderer. The object is always clearly more saturated than table and arm (the vision
encoder selects it by saturation), but shading, highlights, shadows and the hand occlude it.

Frames are RGB uint8 [T, H, W, 3]; `render_frames` is deterministic for a given appearance.
"""

from __future__ import annotations

import colorsys
from dataclasses import asdict, dataclass

import cv2
import numpy as np

from data.motion import Motion
from data.nao import arm_pose
from data.scenario import Scene
from data.world import COLOUR_HUE, OBJECT_HOME, OBJECT_SIZE, TABLE_Z

WIDTH, HEIGHT = 320, 240
NAO_HFOV = float(np.deg2rad(60.97))  # NAO V5 camera horizontal field of view
HEAD_ORIGIN = np.array([0.0, 0.0, 0.1265])  # HeadYaw/HeadPitch joint in the torso frame
BOTTOM_CAMERA_OFFSET = np.array([0.05071, 0.0, 0.01774])  # CameraBottom in the head frame
BOTTOM_CAMERA_PITCH = 0.6929  # CameraBottom looks 39.7 degrees down in the head frame
HEAD_PITCH_LIMITS = (-0.6720, 0.5149)

TABLE_KINDS: tuple[str, ...] = ("wood", "plain", "cloth")

NAO_WHITE = np.array([232.0, 232.0, 226.0])
NAO_GREY = np.array([118.0, 121.0, 128.0])

_TEX_SIZE = 384
_TEX_X = (-0.05, 0.55)  # torso-frame x range covered by the table texture (m)
_TEX_Y = (-0.45, 0.25)  # torso-frame y range
_OPTICAL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])  # body (x fwd) -> optical
_NEAR = 0.03  # near clipping distance (m)


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _hsv_to_rgb(h_deg: float, s: float, v: float) -> np.ndarray:
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
    dice_pips: int  # pips on the dice's top face
    seed: int  # texture and noise
    width: int = WIDTH
    height: int = HEIGHT

    @classmethod
    def sample(cls, rng: np.random.Generator, width: int = WIDTH, height: int = HEIGHT) -> Appearance:
        """A new, widely varied appearance. The camera is aimed near the workspace in front of the arm."""
        hfov = float(np.deg2rad(rng.uniform(52.0, 70.0)))
        offset = tuple(float(v) for v in rng.uniform([-0.02, -0.02, -0.015], [0.02, 0.02, 0.03]))
        aim = np.array([0.13 + rng.uniform(-0.02, 0.02), -0.105 + rng.uniform(-0.025, 0.025), TABLE_Z])
        yaw, pitch = 0.0, 0.3
        for _ in range(3):  # the camera position depends on the head angles it is solved for
            position = HEAD_ORIGIN + np.asarray(offset) + _rot_z(yaw) @ _rot_y(pitch) @ BOTTOM_CAMERA_OFFSET
            d = aim - position
            yaw = float(np.arctan2(d[1], d[0]))
            pitch = float(np.arctan2(-d[2], np.hypot(d[0], d[1]))) - BOTTOM_CAMERA_PITCH
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
            head_pitch=float(np.clip(pitch, *HEAD_PITCH_LIMITS)),
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
        return _hsv_to_rgb(hue + self.object_hue_shift * tolerance, self.object_saturation, value)


@dataclass(frozen=True)
class _Camera:
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
        z = np.maximum(pc[:, 2], _NEAR)
        u = self.focal * pc[:, 0] / z + self.centre[0]
        return np.stack([u, self.focal * pc[:, 1] / z + self.centre[1]], 1)

    def depth(self, points: np.ndarray) -> np.ndarray:
        return self.to_camera(np.atleast_2d(points))[:, 2]

    def table_homography(self) -> np.ndarray:
        """Texel (col, row) of the table texture -> pixel."""
        dx = (_TEX_X[1] - _TEX_X[0]) / _TEX_SIZE
        dy = (_TEX_Y[1] - _TEX_Y[0]) / _TEX_SIZE
        texel_to_world = np.array([[0.0, dx, _TEX_X[0]], [dy, 0.0, _TEX_Y[0]], [0.0, 0.0, TABLE_Z]])
        k = np.array([[self.focal, 0.0, self.centre[0]], [0.0, self.focal, self.centre[1]], [0.0, 0.0, 1.0]])
        return k @ (self.rotation @ texel_to_world + np.outer(self.translation, [0.0, 0.0, 1.0]))


def _camera(app: Appearance, d_yaw: float = 0.0, d_pitch: float = 0.0) -> _Camera:
    head = _rot_z(app.head_yaw + d_yaw) @ _rot_y(app.head_pitch + d_pitch)
    position = HEAD_ORIGIN + np.asarray(app.camera_offset) + head @ BOTTOM_CAMERA_OFFSET
    body = head @ _rot_y(BOTTOM_CAMERA_PITCH) @ _rot_x(app.camera_roll)
    rotation = _OPTICAL @ body.T
    focal = 0.5 * app.width / np.tan(0.5 * app.hfov)
    centre = (0.5 * app.width, 0.5 * app.height)
    return _Camera(rotation, -rotation @ position, position, float(focal), centre)


def head_angles(aim: np.ndarray, camera_offset: tuple[float, float, float]) -> tuple[float, float]:
    """Head yaw and pitch (rad, pitch within the NAO's limits) that point the bottom camera,
    displaced by `camera_offset` (m), at the torso-frame point `aim`: for appearances posed beyond
    `Appearance.sample` (e.g. another robot's camera height) that still look at the workspace."""
    yaw, pitch = 0.0, 0.3
    base = HEAD_ORIGIN + np.asarray(camera_offset)
    for _ in range(3):  # the camera position depends on the head angles it is solved for
        d = np.asarray(aim, dtype=float) - (base + _rot_z(yaw) @ _rot_y(pitch) @ BOTTOM_CAMERA_OFFSET)
        yaw = float(np.arctan2(d[1], d[0]))
        pitch = float(np.arctan2(-d[2], np.hypot(d[0], d[1]))) - BOTTOM_CAMERA_PITCH
    return yaw, float(np.clip(pitch, *HEAD_PITCH_LIMITS))


def project(appearance: Appearance, points: np.ndarray) -> np.ndarray:
    """Pixel coordinates [n,2] of torso-frame points [n,3] in this appearance's (unjittered) camera."""
    return _camera(appearance).project(np.atleast_2d(np.asarray(points, dtype=float)))


def _table_texture(app: Appearance, rng: np.random.Generator) -> np.ndarray:
    """[S,S,3] float32 RGB texture of the table (rows: torso x, columns: torso y)."""
    s = _TEX_SIZE
    low = cv2.resize(rng.normal(0.0, 1.0, (6, 6)).astype(np.float32), (s, s), interpolation=cv2.INTER_CUBIC)
    rows, cols = np.mgrid[0:s, 0:s].astype(np.float32)
    if app.table_kind == "wood":
        across = cols if rng.random() < 0.5 else rows
        warp = across + 10.0 * low
        streaks = np.convolve(rng.normal(0.0, 1.0, 2 * s + 40), np.hanning(9) / 4.0, mode="same")
        idx = np.clip(warp + s // 2, 0, 2 * s + 39).astype(np.int32)
        shade = 1.0 + 0.09 * streaks[idx] + 0.06 * np.sin(warp * rng.uniform(0.15, 0.4))
    elif app.table_kind == "cloth":
        fine = cv2.GaussianBlur(rng.normal(0.0, 1.0, (s, s)).astype(np.float32), (3, 3), 0.8)
        period = rng.uniform(2.5, 5.0)
        weave = np.sin(2 * np.pi * rows / period) * np.sin(2 * np.pi * cols / period)
        shade = 1.0 + 0.07 * fine + 0.05 * weave + 0.04 * low
    else:
        shade = 1.0 + 0.04 * low
    texture = shade[..., None] * _hsv_to_rgb(*app.table_hsv)[None, None, :]
    edge_row = int((app.table_edge - _TEX_X[0]) / (_TEX_X[1] - _TEX_X[0]) * s)
    if edge_row < s:
        texture[edge_row:] = _hsv_to_rgb(*app.background_hsv)
        texture[edge_row : edge_row + 3] *= 0.55  # the table's edge
    return np.clip(texture, 0, 255).astype(np.float32)


def _light_map(app: Appearance) -> np.ndarray:
    """[H,W] smooth brightness: the directional light's gradient and vignetting."""
    v, u = np.mgrid[0 : app.height, 0 : app.width].astype(np.float32)
    un, vn = u / app.width - 0.5, v / app.height - 0.5
    gx, gy = app.light_gradient
    lit = app.ambient + app.light_intensity * app.light_direction[2]
    brightness = lit / (app.ambient + app.light_intensity)
    light = (1.0 + gx * un + gy * vn) * (1.0 - app.vignetting * (un**2 + vn**2) * 2.0) * brightness * 1.1
    return light.astype(np.float32)


def _shade(normal: np.ndarray, app: Appearance) -> float:
    return app.ambient + app.light_intensity * max(0.0, float(np.dot(normal, app.light_direction)))


def _pts(uv: np.ndarray) -> np.ndarray:
    """Pixel coordinates as cv2 points with 4 fractional bits."""
    return np.round(np.clip(uv, -4000, 4000) * 16).astype(np.int32)


def _fill(img: np.ndarray, uv: np.ndarray, colour: np.ndarray) -> None:
    cv2.fillPoly(img, [_pts(uv)], np.clip(colour, 0, 255).tolist(), cv2.LINE_AA, shift=4)


def _outline(shape: str, app: Appearance) -> tuple[np.ndarray, float]:
    """Closed counter-clockwise footprint [n,2] in the object frame (m) and the height (m)."""
    half_x, half_y, height = OBJECT_SIZE[shape]
    k = app.object_scale
    if shape == "banana":
        s = np.linspace(-1.0, 1.0, 24)
        centre = np.stack([app.banana_bend * (1 - s**2), half_y * k * s], 1)
        tangent = np.gradient(centre, axis=0)
        normal = np.stack([tangent[:, 1], -tangent[:, 0]], 1)
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        width = half_x * k * np.clip(1 - s**2, 0.0, 1.0) ** 0.45 + 0.002
        outline = np.concatenate([centre + normal * width[:, None], (centre - normal * width[:, None])[::-1]])
    elif shape == "phone":
        r = 0.006
        a, b = half_x * k - r, half_y * k - r
        t = np.linspace(0, np.pi / 2, 5)
        corners = []
        for (cx, cy), start in zip([(a, b), (-a, b), (-a, -b), (a, -b)], [0, 0.5, 1.0, 1.5], strict=True):
            ang = t + start * np.pi
            corners.append(np.stack([cx + r * np.cos(ang), cy + r * np.sin(ang)], 1))
        outline = np.concatenate(corners)
    else:  # dice
        h = half_x * k
        outline = np.array([[h, h], [-h, h], [-h, -h], [h, -h]])
        height = 2 * h
    area2 = np.sum(outline[:, 0] * np.roll(outline[:, 1], -1) - np.roll(outline[:, 0], -1) * outline[:, 1])
    return (outline if area2 > 0 else outline[::-1]), height


def _to_world(local: np.ndarray, xy: np.ndarray, yaw: float, z: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    world = local @ np.array([[c, s], [-s, c]]) + xy
    return np.column_stack([world, np.full(len(world), z)])


def _draw_prism(
    img: np.ndarray,
    cam: _Camera,
    app: Appearance,
    footprint: np.ndarray,
    z0: float,
    z1: float,
    rgb: np.ndarray,
) -> np.ndarray:
    """Extruded footprint [n,2] (world xy) between heights z0 and z1; returns the top face in pixels."""
    bottom = np.column_stack([footprint, np.full(len(footprint), z0)])
    top = np.column_stack([footprint, np.full(len(footprint), z1)])
    ub, ut = cam.project(bottom), cam.project(top)
    edges = np.roll(footprint, -1, axis=0) - footprint
    normals = np.column_stack([edges[:, 1], -edges[:, 0], np.zeros(len(edges))])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-9)
    mids = 0.5 * (top + np.roll(top, -1, axis=0))
    visible = np.einsum("ij,ij->i", normals, cam.position - mids) > 0
    order = np.argsort(-cam.depth(mids))
    for i in order:
        if visible[i]:
            j = (i + 1) % len(footprint)
            quad = np.array([ub[i], ub[j], ut[j], ut[i]])
            _fill(img, quad, rgb * _shade(normals[i], app))
    _fill(img, ut, rgb * _shade(np.array([0.0, 0.0, 1.0]), app))
    return ut


def _draw_apple(
    img: np.ndarray, cam: _Camera, app: Appearance, xy: np.ndarray, yaw: float, rgb: np.ndarray
) -> None:
    """Ray-cast sphere with Lambert + Phong shading, a stem and a leaf."""
    radius = OBJECT_SIZE["apple"][0] * app.object_scale
    centre = np.array([xy[0], xy[1], TABLE_Z + 0.92 * radius])
    uv = cam.project(centre[None])[0]
    r_px = cam.focal * radius / max(cam.depth(centre)[0], _NEAR) * 1.35
    u0, u1 = int(max(uv[0] - r_px, 0)), int(min(uv[0] + r_px + 1, app.width))
    v0, v1 = int(max(uv[1] - r_px, 0)), int(min(uv[1] + r_px + 1, app.height))
    if u1 <= u0 or v1 <= v0:
        return
    vv, uu = np.mgrid[v0:v1, u0:u1].astype(np.float64)
    rays = np.stack([(uu - cam.centre[0]), (vv - cam.centre[1]), np.full_like(uu, cam.focal)], -1)
    rays = rays @ cam.rotation  # optical -> world directions
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    oc = cam.position - centre
    b = rays @ oc
    disc = b**2 - (oc @ oc - radius**2)
    hit = disc > 0
    if not hit.any():
        return
    dist = -b - np.sqrt(np.where(hit, disc, 0.0))
    normal = (cam.position + rays * dist[..., None] - centre) / radius
    light = np.asarray(app.light_direction)
    lambert = np.clip(normal @ light, 0.0, None)
    reflect = 2 * lambert[..., None] * normal - light
    spec = app.specular * np.clip(np.einsum("...k,...k->...", reflect, -rays), 0, None) ** 24
    colour = rgb * (app.ambient + app.light_intensity * lambert)[..., None] + 255.0 * spec[..., None]
    # soft edge: coverage from how deep the ray enters the sphere
    alpha = np.clip(np.sqrt(np.where(hit, disc, 0.0)) / radius * 6.0, 0.0, 1.0)[..., None]
    roi = img[v0:v1, u0:u1]
    roi[:] = np.clip(roi * (1 - alpha) + colour * alpha, 0, 255).astype(img.dtype)
    top = centre + np.array([0.0, 0.0, 0.9 * radius])
    c, s = np.cos(yaw), np.sin(yaw)
    stem_tip = top + np.array([0.003 * c, 0.003 * s, 0.009])
    leaf_tip = top + np.array([0.013 * -s, 0.013 * c, 0.004])
    p = cam.project(np.array([top, stem_tip, leaf_tip, 0.5 * (top + leaf_tip) + [0.003 * c, 0.003 * s, 0.0]]))
    stem_px = max(1, int(round(cam.focal * 0.0022 / cam.depth(top)[0])))
    cv2.line(img, tuple(_pts(p[0])), tuple(_pts(p[1])), (84.0, 58.0, 36.0), stem_px, cv2.LINE_AA, shift=4)
    _fill(
        img,
        np.array([p[0], p[3], p[2], 2 * p[0] - p[3] + (p[2] - p[0]) * 0.6 - (p[0] - p[3]) * 0.2]),
        _hsv_to_rgb(105.0, 0.65, 0.5) * _shade(np.array([0.0, 0.0, 1.0]), app),
    )


def _draw_object(
    img: np.ndarray, cam: _Camera, app: Appearance, shape: str, xy: np.ndarray, yaw: float, rgb: np.ndarray
) -> None:
    if shape == "apple":
        _draw_apple(img, cam, app, xy, yaw, rgb)
        return
    local, height = _outline(shape, app)
    footprint = _to_world(local, xy, yaw, 0.0)[:, :2]
    top = _draw_prism(img, cam, app, footprint, TABLE_Z, TABLE_Z + height, rgb)
    up = _shade(np.array([0.0, 0.0, 1.0]), app)
    if shape == "phone":  # a dark glossy screen, inset from the rim, keeping a tint of the case
        half_x, half_y, _ = OBJECT_SIZE["phone"]
        k = app.object_scale
        sx0, sx1, sy = half_x * k - 0.008, -half_x * k + 0.005, half_y * k - 0.003
        screen = np.array([[sx0, sy], [sx1, sy], [sx1, -sy], [sx0, -sy]])
        uv = cam.project(_to_world(screen, xy, yaw, TABLE_Z + height + 0.0005))
        _fill(img, uv, rgb * 0.42 * up)
        glare = np.array(
            [
                uv[0] * 0.8 + uv[1] * 0.2,
                uv[0] * 0.6 + uv[1] * 0.4,
                uv[2] * 0.6 + uv[3] * 0.4,
                uv[2] * 0.8 + uv[3] * 0.2,
            ]
        )
        _fill(img, glare, rgb * 0.42 * up + 40.0 * app.specular)
    elif shape == "banana":  # a lit ridge and brown tips
        s = np.linspace(-0.8, 0.8, 12)
        half_y = OBJECT_SIZE["banana"][1] * app.object_scale
        ridge = np.stack([app.banana_bend * (1 - s**2), half_y * s], 1)
        uv = cam.project(_to_world(ridge, xy, yaw, TABLE_Z + height + 0.001))
        width = max(1, int(round(cam.focal * 0.005 / cam.depth(np.append(xy, TABLE_Z))[0])))
        ridge_rgb = np.clip(rgb * up * 1.18, 0, 255).tolist()
        cv2.polylines(img, [_pts(uv)], False, ridge_rgb, width, cv2.LINE_AA, 4)
        n = len(top) // 2
        for tip in (top[0], top[n - 1]):
            cv2.circle(img, tuple(_pts(tip)), 2 * 16, (70.0, 52.0, 30.0), -1, cv2.LINE_AA, shift=4)
    elif shape == "dice":
        _draw_pips(img, cam, app, xy, yaw, height)


_PIP_LAYOUT: dict[int, list[tuple[float, float]]] = {
    1: [(0, 0)],
    2: [(-1, -1), (1, 1)],
    3: [(-1, -1), (0, 0), (1, 1)],
    4: [(-1, -1), (-1, 1), (1, -1), (1, 1)],
    5: [(-1, -1), (-1, 1), (0, 0), (1, -1), (1, 1)],
    6: [(-1, -1), (-1, 0), (-1, 1), (1, -1), (1, 0), (1, 1)],
}


def _draw_pips(
    img: np.ndarray, cam: _Camera, app: Appearance, xy: np.ndarray, yaw: float, side: float
) -> None:
    """White pips on the top face and on the side faces that face the camera."""
    half = side / 2
    spacing = half * 0.55
    faces = [  # (centre offset, in-plane axes u and v, normal)
        (np.array([0.0, 0.0, half]), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), app.dice_pips),
        (np.array([-half, 0.0, 0.0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), 7 - app.dice_pips),
        (np.array([half, 0.0, 0.0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), 7 - app.dice_pips),
        (np.array([0.0, -half, 0.0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), 1 + app.dice_pips % 6),
        (np.array([0.0, half, 0.0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), 6 - app.dice_pips % 6),
    ]
    rot = _rot_z(yaw)
    centre = np.array([xy[0], xy[1], TABLE_Z + half])
    for offset, u, v, count in faces:
        face_centre = centre + rot @ offset
        normal = rot @ offset / half
        if np.dot(normal, cam.position - face_centre) <= 0:
            continue
        layout = np.array(_PIP_LAYOUT[count], dtype=float)
        pts = face_centre + spacing * (layout[:, :1] * (rot @ u) + layout[:, 1:] * (rot @ v))
        uv = cam.project(pts)
        r_px = max(1.0, cam.focal * half * 0.16 / cam.depth(face_centre)[0])
        grey = 240.0 * _shade(normal, app)
        for p in uv:
            cv2.circle(img, tuple(_pts(p)), int(r_px * 16), (grey, grey, grey), -1, cv2.LINE_AA, shift=4)


def _clip_segment(cam: _Camera, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The part of segment a-b in front of the near plane (torso frame), or None."""
    da, db = cam.depth(a)[0], cam.depth(b)[0]
    if da < _NEAR and db < _NEAR:
        return None
    if da < _NEAR:
        a = a + (b - a) * (_NEAR - da) / (db - da)
    elif db < _NEAR:
        b = b + (a - b) * (_NEAR - db) / (da - db)
    return a, b


def _draw_capsule(
    img: np.ndarray, cam: _Camera, a: np.ndarray, b: np.ndarray, radius: float, rgb: np.ndarray
) -> None:
    """A shaded cylinder from a to b: a darker rim and a lighter core."""
    clipped = _clip_segment(cam, a, b)
    if clipped is None:
        return
    a, b = clipped
    uv = cam.project(np.array([a, b]))
    depth = max(float(np.mean(cam.depth(np.array([a, b])))), _NEAR)
    width = int(np.clip(2 * cam.focal * radius / depth, 1, 400))
    pa, pb = tuple(_pts(uv[0])), tuple(_pts(uv[1]))
    cv2.line(img, pa, pb, (rgb * 0.62).tolist(), width, cv2.LINE_AA, shift=4)
    cv2.line(img, pa, pb, (rgb * 0.86).tolist(), max(1, int(width * 0.72)), cv2.LINE_AA, shift=4)
    cv2.line(img, pa, pb, rgb.tolist(), max(1, int(width * 0.35)), cv2.LINE_AA, shift=4)


def _box_corners(centre: np.ndarray, rot: np.ndarray, half: np.ndarray) -> np.ndarray:
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    return centre + (signs * half) @ rot.T


_BOX_FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def _draw_box(img: np.ndarray, cam: _Camera, app: Appearance, corners: np.ndarray, rgb: np.ndarray) -> None:
    """A flat-shaded box from its 8 corners (order of `_box_corners`)."""
    if np.any(cam.depth(corners) < _NEAR):
        return
    uv = cam.project(corners)
    centre = corners.mean(axis=0)
    faces = []
    for face in _BOX_FACES:
        pts = corners[list(face)]
        mid = pts.mean(axis=0)
        normal = mid - centre
        normal /= max(np.linalg.norm(normal), 1e-9)
        if np.dot(normal, cam.position - mid) > 0:
            faces.append((cam.depth(mid)[0], face, normal))
    for _, face, normal in sorted(faces, key=lambda f: -f[0]):
        _fill(img, uv[list(face)], rgb * min(1.15, _shade(normal, app)))


# NAO hand as two boxes in the hand frame (from the wrist joint): palm and fingers (m)
_PALM_CENTRE, _PALM_HALF = np.array([0.028, 0.0, -0.006]), np.array([0.028, 0.011, 0.019])
_FINGERS_CENTRE, _FINGERS_HALF = np.array([0.07, 0.0, -0.01]), np.array([0.016, 0.007, 0.015])


@dataclass(frozen=True)
class _Arm:
    """Arm geometry of one frame: FK positions, palm and finger box corners (torso frame)."""

    points: dict[str, np.ndarray]
    palm: np.ndarray
    fingers: np.ndarray

    @classmethod
    def at(cls, q: np.ndarray) -> _Arm:
        points, rot = arm_pose(q)
        wrist = points["wrist"]
        palm = _box_corners(wrist + rot @ _PALM_CENTRE, rot, _PALM_HALF)
        fingers = _box_corners(wrist + rot @ _FINGERS_CENTRE, rot, _FINGERS_HALF)
        return cls(points, palm, fingers)


def _draw_arm(img: np.ndarray, cam: _Camera, app: Appearance, arm: _Arm) -> None:
    p = arm.points
    _draw_capsule(img, cam, p["shoulder"], p["elbow"], 0.027, NAO_WHITE)
    _draw_capsule(img, cam, p["elbow"], p["wrist"], 0.022, NAO_WHITE)
    _draw_capsule(img, cam, p["elbow"], p["elbow"] + 1e-4, 0.024, NAO_GREY)
    _draw_box(img, cam, app, arm.fingers, NAO_GREY * 1.25)
    _draw_box(img, cam, app, arm.palm, NAO_GREY * 1.4)


def _on_table(points: np.ndarray, light: np.ndarray) -> np.ndarray:
    """Shadow of points [n,3] cast on the table plane along the light direction."""
    return points - light[None, :] * ((points[:, 2] - TABLE_Z) / light[2])[:, None]


def _draw_shadows(
    mask: np.ndarray, cam: _Camera, app: Appearance, scene: Scene, xy: np.ndarray, yaw: float, arm: _Arm
) -> None:
    light = np.asarray(app.light_direction)
    if scene.shape == "apple":
        r = OBJECT_SIZE["apple"][0] * app.object_scale
        ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        local = np.stack([r * np.cos(ang), r * np.sin(ang)], 1)
        height = 1.9 * r
    else:
        local, height = _outline(scene.shape, app)
    base = _to_world(local, xy, yaw, TABLE_Z)
    raised = _to_world(local, xy, yaw, TABLE_Z + 0.8 * height)
    hull = cv2.convexHull(cam.project(np.concatenate([base, _on_table(raised, light)])).astype(np.float32))
    cv2.fillPoly(mask, [_pts(hull[:, 0])], 255, cv2.LINE_AA, shift=4)
    p = arm.points
    chain = np.array([p["shoulder"], p["elbow"], p["wrist"], arm.fingers.mean(axis=0)])
    flat = _on_table(chain, light)
    for (a, b), radius in zip([(0, 1), (1, 2), (2, 3)], (0.027, 0.022, 0.02), strict=True):
        clipped = _clip_segment(cam, flat[a], flat[b])
        if clipped is None:
            continue
        uv = cam.project(np.array(clipped))
        width = int(np.clip(2 * cam.focal * radius / max(cam.depth(clipped[1])[0], _NEAR), 1, 400))
        cv2.line(mask, tuple(_pts(uv[0])), tuple(_pts(uv[1])), 255, width, cv2.LINE_AA, shift=4)


_MARGIN = 12  # pixels of table rendered beyond each image border, for the head jitter


def _background(app: Appearance, cam: _Camera, rng: np.random.Generator) -> np.ndarray:
    """The lit, empty table as seen by `cam`, with a margin: uint8 [H+2m, W+2m, 3]."""
    texture = _table_texture(app, rng)
    background = tuple(float(v) for v in _hsv_to_rgb(*app.background_hsv))
    shift = np.array([[1.0, 0.0, _MARGIN], [0.0, 1.0, _MARGIN], [0.0, 0.0, 1.0]])
    size = (app.width + 2 * _MARGIN, app.height + 2 * _MARGIN)
    table = cv2.warpPerspective(
        texture,
        shift @ cam.table_homography(),
        size,
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=background,
    )
    light = cv2.copyMakeBorder(_light_map(app), _MARGIN, _MARGIN, _MARGIN, _MARGIN, cv2.BORDER_REPLICATE)
    return np.clip(table * light[..., None], 0, 255).astype(np.uint8)


def render_frames(scene: Scene, motion: Motion, appearance: Appearance) -> np.ndarray:
    """The camera's view at every time step of `motion`: uint8 [T, height, width, 3] RGB."""
    app = appearance
    rng = np.random.default_rng(app.seed)
    base_cam = _camera(app)
    table = _background(app, base_cam, rng)
    rgb = app.object_rgb(scene.colour)
    gains = tuple(float(g) * app.exposure for g in app.white_balance) + (0.0,)
    n = len(motion.joints)
    # head jitter: a slow random walk of the head angles (rad), rendered exactly for object and arm
    # and as the matching image shift for the table
    shake = np.cumsum(rng.normal(0.0, app.shake, (n, 2)), axis=0) * 0.5
    noise = rng.normal(0.0, app.noise_sigma, (app.height + 32, app.width + 32, 3))
    noise_up = np.clip(noise, 0, 255).astype(np.uint8)
    noise_down = np.clip(-noise, 0, 255).astype(np.uint8)
    offsets = rng.integers(0, 32, (n, 2))
    frames = np.empty((n, app.height, app.width, 3), dtype=np.uint8)
    mask = np.empty((app.height, app.width), dtype=np.uint8)
    anchor = np.append(OBJECT_HOME, TABLE_Z)
    for t in range(n):
        cam = _camera(app, shake[t, 0], shake[t, 1]) if app.shake > 0 else base_cam
        dx, dy = np.clip(
            np.round(cam.project(anchor[None])[0] - base_cam.project(anchor[None])[0]), -_MARGIN, _MARGIN
        ).astype(int)
        img = table[_MARGIN - dy : _MARGIN - dy + app.height, _MARGIN - dx : _MARGIN - dx + app.width].copy()
        arm = _Arm.at(motion.joints[t])
        xy, yaw = motion.object_xy[t], float(motion.object_yaw[t])
        mask[:] = 0
        _draw_shadows(mask, cam, app, scene, xy, yaw, arm)
        x0, y0, w, h = cv2.boundingRect(mask)
        if w > 0 and h > 0:
            x0, y0 = max(x0 - 4, 0), max(y0 - 4, 0)
            box = (slice(y0, y0 + h + 8), slice(x0, x0 + w + 8))
            light = cv2.convertScaleAbs(cv2.blur(mask[box], (7, 7)), alpha=-app.shadow_strength, beta=255)
            img[box] = cv2.multiply(img[box], cv2.merge([light, light, light]), scale=1.0 / 255.0)
        # the arm is drawn after the object unless the hand is behind it and low (e.g. pulling)
        hand = arm.points["hand"]
        behind = cam.depth(hand)[0] > cam.depth(np.append(xy, TABLE_Z))[0] + 0.01
        hand_behind = bool(behind and hand[2] < TABLE_Z + 0.05)
        if hand_behind:
            _draw_arm(img, cam, app, arm)
        _draw_object(img, cam, app, scene.shape, xy, yaw, rgb)
        if not hand_behind:
            _draw_arm(img, cam, app, arm)
        img = cv2.multiply(img, gains)  # exposure and white balance
        if app.blur_sigma > 0.3:
            img = cv2.GaussianBlur(img, (0, 0), app.blur_sigma)
        oy, ox = offsets[t]
        img = cv2.subtract(
            cv2.add(img, noise_up[oy : oy + app.height, ox : ox + app.width]),
            noise_down[oy : oy + app.height, ox : ox + app.width],
        )
        frames[t] = img
    return frames
