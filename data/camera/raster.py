"""Drawing in the camera image with OpenCV: filled and shaded polygons, the objects' footprints and
extruded prisms, the arm as capsules and boxes, the soft shadows object and arm cast on the table,
and the lit, textured empty table every frame starts from."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from data.camera.camera import NEAR, TEX_SIZE, TEX_X, Appearance, Camera, hsv_to_rgb
from data.nao import arm_pose
from data.scenario import Scene
from data.world import World

NAO_WHITE = np.array([232.0, 232.0, 226.0])
NAO_GREY = np.array([118.0, 121.0, 128.0])


def _table_texture(app: Appearance, rng: np.random.Generator) -> np.ndarray:
    """[S,S,3] float32 RGB texture of the table (rows: torso x, columns: torso y)."""
    s = TEX_SIZE
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
    texture = shade[..., None] * hsv_to_rgb(*app.table_hsv)[None, None, :]
    edge_row = int((app.table_edge - TEX_X[0]) / (TEX_X[1] - TEX_X[0]) * s)
    if edge_row < s:
        texture[edge_row:] = hsv_to_rgb(*app.background_hsv)
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


def shading(normal: np.ndarray, app: Appearance) -> float:
    return app.ambient + app.light_intensity * max(0.0, float(np.dot(normal, app.light_direction)))


def cv_pts(uv: np.ndarray) -> np.ndarray:
    """Pixel coordinates as cv2 points with 4 fractional bits."""
    return np.round(np.clip(uv, -4000, 4000) * 16).astype(np.int32)


def fill(img: np.ndarray, uv: np.ndarray, colour: np.ndarray) -> None:
    cv2.fillPoly(img, [cv_pts(uv)], np.clip(colour, 0, 255).tolist(), cv2.LINE_AA, shift=4)


def _rounded_rectangle(a: float, b: float, r: float) -> np.ndarray:
    """Outline of a rectangle with corners of radius `r` whose straight edges end at (+-a, +-b)."""
    t = np.linspace(0, np.pi / 2, 5)
    corners = []
    for (cx, cy), start in zip([(a, b), (-a, b), (-a, -b), (a, -b)], [0, 0.5, 1.0, 1.5], strict=True):
        ang = t + start * np.pi
        corners.append(np.stack([cx + r * np.cos(ang), cy + r * np.sin(ang)], 1))
    return np.concatenate(corners)


def object_outline(shape: str, app: Appearance, world: World) -> tuple[np.ndarray, float]:
    """Closed counter-clockwise footprint [n,2] in the object frame (m) and the height (m)."""
    half_x, half_y, height = world.size(shape)
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
        outline = _rounded_rectangle(half_x * k - r, half_y * k - r, r)
    else:  # dice
        h = half_x * k
        r = world.dice_round * h
        outline = (
            _rounded_rectangle(h - r, h - r, r) if r > 0 else np.array([[h, h], [-h, h], [-h, -h], [h, -h]])
        )
        height = 2 * h
    area2 = np.sum(outline[:, 0] * np.roll(outline[:, 1], -1) - np.roll(outline[:, 0], -1) * outline[:, 1])
    return (outline if area2 > 0 else outline[::-1]), height


def to_world(local: np.ndarray, xy: np.ndarray, yaw: float, z: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    world = local @ np.array([[c, s], [-s, c]]) + xy
    return np.column_stack([world, np.full(len(world), z)])


def draw_prism(
    img: np.ndarray,
    cam: Camera,
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
            fill(img, quad, rgb * shading(normals[i], app))
    fill(img, ut, rgb * shading(np.array([0.0, 0.0, 1.0]), app))
    return ut


def _clip_segment(cam: Camera, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The part of segment a-b in front of the near plane (torso frame), or None."""
    da, db = cam.depth(a)[0], cam.depth(b)[0]
    if da < NEAR and db < NEAR:
        return None
    if da < NEAR:
        a = a + (b - a) * (NEAR - da) / (db - da)
    elif db < NEAR:
        b = b + (a - b) * (NEAR - db) / (da - db)
    return a, b


def _draw_capsule(
    img: np.ndarray, cam: Camera, a: np.ndarray, b: np.ndarray, radius: float, rgb: np.ndarray
) -> None:
    """A shaded cylinder from a to b: a darker rim and a lighter core."""
    clipped = _clip_segment(cam, a, b)
    if clipped is None:
        return
    a, b = clipped
    uv = cam.project(np.array([a, b]))
    depth = max(float(np.mean(cam.depth(np.array([a, b])))), NEAR)
    width = int(np.clip(2 * cam.focal * radius / depth, 1, 400))
    pa, pb = tuple(cv_pts(uv[0])), tuple(cv_pts(uv[1]))
    cv2.line(img, pa, pb, (rgb * 0.62).tolist(), width, cv2.LINE_AA, shift=4)
    cv2.line(img, pa, pb, (rgb * 0.86).tolist(), max(1, int(width * 0.72)), cv2.LINE_AA, shift=4)
    cv2.line(img, pa, pb, rgb.tolist(), max(1, int(width * 0.35)), cv2.LINE_AA, shift=4)


def _box_corners(centre: np.ndarray, rot: np.ndarray, half: np.ndarray) -> np.ndarray:
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    return centre + (signs * half) @ rot.T


_BOX_FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def _draw_box(img: np.ndarray, cam: Camera, app: Appearance, corners: np.ndarray, rgb: np.ndarray) -> None:
    """A flat-shaded box from its 8 corners (order of `_box_corners`)."""
    if np.any(cam.depth(corners) < NEAR):
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
        fill(img, uv[list(face)], rgb * min(1.15, shading(normal, app)))


# NAO hand as two boxes in the hand frame (from the wrist joint): palm and fingers (m)
_PALM_CENTRE, _PALM_HALF = np.array([0.028, 0.0, -0.006]), np.array([0.028, 0.011, 0.019])
_FINGERS_CENTRE, _FINGERS_HALF = np.array([0.07, 0.0, -0.01]), np.array([0.016, 0.007, 0.015])


@dataclass(frozen=True)
class Arm:
    """Arm geometry of one frame: FK positions, palm and finger box corners (torso frame)."""

    points: dict[str, np.ndarray]
    palm: np.ndarray
    fingers: np.ndarray

    @classmethod
    def at(cls, q: np.ndarray) -> Arm:
        points, rot = arm_pose(q)
        wrist = points["wrist"]
        palm = _box_corners(wrist + rot @ _PALM_CENTRE, rot, _PALM_HALF)
        fingers = _box_corners(wrist + rot @ _FINGERS_CENTRE, rot, _FINGERS_HALF)
        return cls(points, palm, fingers)


def draw_arm(img: np.ndarray, cam: Camera, app: Appearance, arm: Arm) -> None:
    p = arm.points
    _draw_capsule(img, cam, p["shoulder"], p["elbow"], 0.027, NAO_WHITE)
    _draw_capsule(img, cam, p["elbow"], p["wrist"], 0.022, NAO_WHITE)
    _draw_capsule(img, cam, p["elbow"], p["elbow"] + 1e-4, 0.024, NAO_GREY)
    _draw_box(img, cam, app, arm.fingers, NAO_GREY * 1.25)
    _draw_box(img, cam, app, arm.palm, NAO_GREY * 1.4)


def _on_table(points: np.ndarray, light: np.ndarray, table_z: float) -> np.ndarray:
    """Shadow of points [n,3] cast on the table plane (height `table_z`) along the light direction."""
    return points - light[None, :] * ((points[:, 2] - table_z) / light[2])[:, None]


def draw_shadows(
    mask: np.ndarray,
    cam: Camera,
    app: Appearance,
    world: World,
    scene: Scene,
    xy: np.ndarray,
    yaw: float,
    arm: Arm,
) -> None:
    light = np.asarray(app.light_direction)
    table_z = world.table_z
    if scene.shape == "apple":
        r = world.size("apple")[0] * app.object_scale
        ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        local = np.stack([r * np.cos(ang), r * np.sin(ang)], 1)
        height = 1.9 * r
    else:
        local, height = object_outline(scene.shape, app, world)
    base = to_world(local, xy, yaw, table_z)
    raised = to_world(local, xy, yaw, table_z + 0.8 * height)
    hull = cv2.convexHull(
        cam.project(np.concatenate([base, _on_table(raised, light, table_z)])).astype(np.float32)
    )
    cv2.fillPoly(mask, [cv_pts(hull[:, 0])], 255, cv2.LINE_AA, shift=4)
    p = arm.points
    chain = np.array([p["shoulder"], p["elbow"], p["wrist"], arm.fingers.mean(axis=0)])
    flat = _on_table(chain, light, table_z)
    for (a, b), radius in zip([(0, 1), (1, 2), (2, 3)], (0.027, 0.022, 0.02), strict=True):
        clipped = _clip_segment(cam, flat[a], flat[b])
        if clipped is None:
            continue
        uv = cam.project(np.array(clipped))
        width = int(np.clip(2 * cam.focal * radius / max(cam.depth(clipped[1])[0], NEAR), 1, 400))
        cv2.line(mask, tuple(cv_pts(uv[0])), tuple(cv_pts(uv[1])), 255, width, cv2.LINE_AA, shift=4)


MARGIN = 12  # pixels of table rendered beyond each image border, for the head jitter


def empty_table(app: Appearance, cam: Camera, rng: np.random.Generator, table_z: float) -> np.ndarray:
    """The lit, empty table (its top at `table_z`) as seen by `cam`, with a margin: uint8 [H+2m, W+2m, 3]."""
    texture = _table_texture(app, rng)
    background = tuple(float(v) for v in hsv_to_rgb(*app.background_hsv))
    shift = np.array([[1.0, 0.0, MARGIN], [0.0, 1.0, MARGIN], [0.0, 0.0, 1.0]])
    size = (app.width + 2 * MARGIN, app.height + 2 * MARGIN)
    table = cv2.warpPerspective(
        texture,
        shift @ cam.table_homography(table_z),
        size,
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=background,
    )
    light = cv2.copyMakeBorder(_light_map(app), MARGIN, MARGIN, MARGIN, MARGIN, cv2.BORDER_REPLICATE)
    return np.clip(table * light[..., None], 0, 255).astype(np.uint8)
