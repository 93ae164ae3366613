"""The four objects as the camera sees them: a ray-cast apple with stem and leaf, and the extruded
banana (lit ridge, brown tips), dice (pips on the faces towards the camera) and phone (glossy screen)."""

from __future__ import annotations

import cv2
import numpy as np

from data.camera.camera import NEAR, Appearance, Camera, hsv_to_rgb, rot_z
from data.camera.raster import cv_pts, draw_prism, fill, object_outline, shading, to_world
from data.world import World


def _draw_apple(
    img: np.ndarray, cam: Camera, app: Appearance, world: World, xy: np.ndarray, yaw: float, rgb: np.ndarray
) -> None:
    """Ray-cast sphere with Lambert + Phong shading, a stem and a leaf (if the world's apple has them)."""
    radius = world.size("apple")[0] * app.object_scale
    centre = np.array([xy[0], xy[1], world.table_z + 0.92 * radius])
    uv = cam.project(centre[None])[0]
    r_px = cam.focal * radius / max(cam.depth(centre)[0], NEAR) * 1.35
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
    if world.apple_stem:
        _draw_stem(img, cam, app, centre, radius, yaw)


def _draw_stem(
    img: np.ndarray, cam: Camera, app: Appearance, centre: np.ndarray, radius: float, yaw: float
) -> None:
    """The apple's stem and leaf on top of the sphere at `centre`."""
    top = centre + np.array([0.0, 0.0, 0.9 * radius])
    c, s = np.cos(yaw), np.sin(yaw)
    stem_tip = top + np.array([0.003 * c, 0.003 * s, 0.009])
    leaf_tip = top + np.array([0.013 * -s, 0.013 * c, 0.004])
    p = cam.project(np.array([top, stem_tip, leaf_tip, 0.5 * (top + leaf_tip) + [0.003 * c, 0.003 * s, 0.0]]))
    stem_px = max(1, int(round(cam.focal * 0.0022 / cam.depth(top)[0])))
    cv2.line(img, tuple(cv_pts(p[0])), tuple(cv_pts(p[1])), (84.0, 58.0, 36.0), stem_px, cv2.LINE_AA, shift=4)
    fill(
        img,
        np.array([p[0], p[3], p[2], 2 * p[0] - p[3] + (p[2] - p[0]) * 0.6 - (p[0] - p[3]) * 0.2]),
        hsv_to_rgb(105.0, 0.65, 0.5) * shading(np.array([0.0, 0.0, 1.0]), app),
    )


def draw_object(
    img: np.ndarray,
    cam: Camera,
    app: Appearance,
    world: World,
    shape: str,
    xy: np.ndarray,
    yaw: float,
    rgb: np.ndarray,
) -> None:
    if shape == "apple":
        _draw_apple(img, cam, app, world, xy, yaw, rgb)
        return
    local, height = object_outline(shape, app, world)
    footprint = to_world(local, xy, yaw, 0.0)[:, :2]
    table_z = world.table_z
    top = draw_prism(img, cam, app, footprint, table_z, table_z + height, rgb)
    up = shading(np.array([0.0, 0.0, 1.0]), app)
    if shape == "phone" and world.phone_screen != "none":  # a glossy screen, inset from the rim
        half_x, half_y, _ = world.size("phone")
        k = app.object_scale
        sx0, sx1, sy = half_x * k - 0.008, -half_x * k + 0.005, half_y * k - 0.003
        screen = np.array([[sx0, sy], [sx1, sy], [sx1, -sy], [sx0, -sy]])
        uv = cam.project(to_world(screen, xy, yaw, table_z + height + 0.0005))
        shade = 0.42 if world.phone_screen == "dark" else 0.7  # keeping a tint of the case
        fill(img, uv, rgb * shade * up)
        glare = np.array(
            [
                uv[0] * 0.8 + uv[1] * 0.2,
                uv[0] * 0.6 + uv[1] * 0.4,
                uv[2] * 0.6 + uv[3] * 0.4,
                uv[2] * 0.8 + uv[3] * 0.2,
            ]
        )
        fill(img, glare, rgb * shade * up + 40.0 * app.specular)
    elif shape == "banana":  # a lit ridge and brown tips
        s = np.linspace(-0.8, 0.8, 12)
        half_y = world.size("banana")[1] * app.object_scale
        ridge = np.stack([app.banana_bend * (1 - s**2), half_y * s], 1)
        uv = cam.project(to_world(ridge, xy, yaw, table_z + height + 0.001))
        width = max(1, int(round(cam.focal * 0.005 / cam.depth(np.append(xy, table_z))[0])))
        ridge_rgb = np.clip(rgb * up * 1.18, 0, 255).tolist()
        cv2.polylines(img, [cv_pts(uv)], False, ridge_rgb, width, cv2.LINE_AA, 4)
        n = len(top) // 2
        for tip in (top[0], top[n - 1]):
            cv2.circle(img, tuple(cv_pts(tip)), 2 * 16, (70.0, 52.0, 30.0), -1, cv2.LINE_AA, shift=4)
    elif shape == "dice" and app.dice_pips > 0:
        _draw_pips(img, cam, app, xy, yaw, table_z, height)


_PIP_LAYOUT: dict[int, list[tuple[float, float]]] = {
    1: [(0, 0)],
    2: [(-1, -1), (1, 1)],
    3: [(-1, -1), (0, 0), (1, 1)],
    4: [(-1, -1), (-1, 1), (1, -1), (1, 1)],
    5: [(-1, -1), (-1, 1), (0, 0), (1, -1), (1, 1)],
    6: [(-1, -1), (-1, 0), (-1, 1), (1, -1), (1, 0), (1, 1)],
}


def _draw_pips(
    img: np.ndarray, cam: Camera, app: Appearance, xy: np.ndarray, yaw: float, table_z: float, side: float
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
    rot = rot_z(yaw)
    centre = np.array([xy[0], xy[1], table_z + half])
    for offset, u, v, count in faces:
        face_centre = centre + rot @ offset
        normal = rot @ offset / half
        if np.dot(normal, cam.position - face_centre) <= 0:
            continue
        layout = np.array(_PIP_LAYOUT[count], dtype=float)
        pts = face_centre + spacing * (layout[:, :1] * (rot @ u) + layout[:, 1:] * (rot @ v))
        uv = cam.project(pts)
        r_px = max(1.0, cam.focal * half * 0.16 / cam.depth(face_centre)[0])
        grey = 240.0 * shading(normal, app)
        for p in uv:
            cv2.circle(img, tuple(cv_pts(p)), int(r_px * 16), (grey, grey, grey), -1, cv2.LINE_AA, shift=4)
