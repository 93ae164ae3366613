"""`render_frames`: a motion seen through an appearance, frame by frame, with head jitter, shadows,
the arm in front of or behind the object, exposure, white balance, blur and sensor noise."""

from __future__ import annotations

import cv2
import numpy as np

from data.camera.camera import Appearance, camera_of
from data.camera.objects import draw_object
from data.camera.raster import MARGIN, Arm, draw_arm, draw_shadows, empty_table
from data.motion import Motion
from data.scenario import Scene
from data.world import PAPER_WORLD, World


def render_frames(
    scene: Scene, motion: Motion, appearance: Appearance, world: World = PAPER_WORLD
) -> np.ndarray:
    """The camera's view at every time step of `motion` in `world` (table and object; default the
    paper's): uint8 [T, height, width, 3] RGB."""
    app = appearance
    table_z = world.table_z
    rng = np.random.default_rng(app.seed)
    base_cam = camera_of(app)
    table = empty_table(app, base_cam, rng, table_z)
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
    anchor = np.append(world.object_home, table_z)
    for t in range(n):
        cam = camera_of(app, shake[t, 0], shake[t, 1]) if app.shake > 0 else base_cam
        dx, dy = np.clip(
            np.round(cam.project(anchor[None])[0] - base_cam.project(anchor[None])[0]), -MARGIN, MARGIN
        ).astype(int)
        img = table[MARGIN - dy : MARGIN - dy + app.height, MARGIN - dx : MARGIN - dx + app.width].copy()
        arm = Arm.at(motion.joints[t])
        xy, yaw = motion.object_xy[t], float(motion.object_yaw[t])
        mask[:] = 0
        draw_shadows(mask, cam, app, world, scene, xy, yaw, arm)
        x0, y0, w, h = cv2.boundingRect(mask)
        if w > 0 and h > 0:
            x0, y0 = max(x0 - 4, 0), max(y0 - 4, 0)
            box = (slice(y0, y0 + h + 8), slice(x0, x0 + w + 8))
            light = cv2.convertScaleAbs(cv2.blur(mask[box], (7, 7)), alpha=-app.shadow_strength, beta=255)
            img[box] = cv2.multiply(img[box], cv2.merge([light, light, light]), scale=1.0 / 255.0)
        # the arm is drawn after the object unless the hand is behind it and low (e.g. pulling)
        hand = arm.points["hand"]
        behind = cam.depth(hand)[0] > cam.depth(np.append(xy, table_z))[0] + 0.01
        hand_behind = bool(behind and hand[2] < table_z + 0.05)
        if hand_behind:
            draw_arm(img, cam, app, arm)
        draw_object(img, cam, app, world, scene.shape, xy, yaw, rgb)
        if not hand_behind:
            draw_arm(img, cam, app, arm)
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
