"""The 3D scene (viser): the NAO's right arm replaying a recording over a table and its object.

`SceneViewer` owns its viser server and every handle it adds. The arm is drawn from primitives
placed by `data.nao.forward_kinematics` (links as boxes, joints as spheres), the
same chain as the URDF. One time cursor is shared by the 3D view's own controls and the web page:
`show(...)` loads a recording, `seek(t)`, `play()`, `pause()`, `set_speed(x)` move it, and every
change is sent to the listeners (the page's WebSocket) so the camera frame, the plots and the
phoneme being produced follow it.

    >>> viewer = SceneViewer(forward_kinematics)          # doctest: +SKIP
    >>> viewer.show("slide-red-apple-2", joints, FPS, "red", "apple")
    >>> viewer.seek(1.5); viewer.play()
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import viser

from data.world import FPS, TABLE_Z, colour_rgb

logger = logging.getLogger(__name__)

ARM_RGB = (225, 225, 230)
JOINT_RGB = (90, 95, 110)
TABLE_RGB = (170, 130, 90)
KEYPOINTS = ("shoulder", "elbow", "wrist", "hand")


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port nobody listens on right now (the OS picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def _x_to(direction: np.ndarray) -> tuple[float, float, float, float]:
    """Quaternion (w, x, y, z) turning the x axis onto `direction`."""
    d = direction / (np.linalg.norm(direction) + 1e-12)
    axis = np.cross([1.0, 0.0, 0.0], d)
    s = np.linalg.norm(axis)
    if s < 1e-9:
        return (1.0, 0.0, 0.0, 0.0) if d[0] > 0 else (0.0, 0.0, 0.0, 1.0)
    angle = np.arctan2(s, d[0])
    v = axis / s * np.sin(angle / 2)
    return (float(np.cos(angle / 2)), float(v[0]), float(v[1]), float(v[2]))


@dataclass
class Cursor:
    """The shared time cursor."""

    source: str | None = None
    t: float = 0.0
    duration_s: float = 0.0
    playing: bool = False
    speed: float = 1.0


class SceneViewer:
    """A viser server on 127.0.0.1 showing one recording at a time, with play / pause / scrub / speed."""

    def __init__(self, forward_kinematics: Callable[[np.ndarray], dict[str, np.ndarray]]) -> None:
        self._fk = forward_kinematics
        self.server = viser.ViserServer(host="127.0.0.1", port=free_port(), label="MultiMTRNN", verbose=False)
        self.port = self.server.get_port()  # viser moves on silently if the port was taken meanwhile
        self.cursor = Cursor()
        self._lock = threading.RLock()
        self._keypoints: np.ndarray | None = None  # [T, 4, 3]
        self._fps = FPS
        self._listeners: list[Callable[[dict], None]] = []
        self._updating_gui = False
        self._build_scene()
        self._build_gui()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="viewer-playback", daemon=True)
        self._thread.start()
        logger.info("3D viewer (viser) on 127.0.0.1:%d", self.port)

    # scene
    def _build_scene(self) -> None:
        scene = self.server.scene
        scene.set_up_direction("+z")
        self.server.initial_camera.position = (0.42, -0.55, 0.3)
        self.server.initial_camera.look_at = (0.18, -0.08, 0.02)
        self.server.gui.configure_theme(
            control_layout="collapsible", control_width="small", show_logo=False, show_share_button=False
        )
        self.table = scene.add_box(
            "/table", color=TABLE_RGB, dimensions=(0.5, 0.7, 0.02), position=(0.2, -0.1, -0.1)
        )
        self.torso = scene.add_box(
            "/torso", color=(200, 200, 205), dimensions=(0.1, 0.12, 0.2), position=(-0.03, 0.0, 0.03)
        )
        self.head = scene.add_icosphere("/head", radius=0.06, color=(235, 235, 240), position=(-0.02, 0, 0.2))
        self.links = [
            scene.add_box(f"/arm/link{k}", color=ARM_RGB, dimensions=(0.1, 0.03, 0.03)) for k in range(3)
        ]
        self.joints = [
            scene.add_icosphere(f"/arm/{name}", radius=0.022 if name != "hand" else 0.026, color=JOINT_RGB)
            for name in KEYPOINTS
        ]
        self.objects: dict[str, Any] = {}

    def _build_gui(self) -> None:
        gui = self.server.gui
        self.gui_title = gui.add_markdown("**No recording loaded.**")
        self.gui_play = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY)
        self.gui_pause = gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE)
        self.gui_time = gui.add_slider("Time (s)", min=0.0, max=1.0, step=0.05, initial_value=0.0)
        self.gui_speed = gui.add_slider("Speed", min=0.25, max=4.0, step=0.25, initial_value=1.0)
        self.gui_play.on_click(lambda _: self.play())
        self.gui_pause.on_click(lambda _: self.pause())

        @self.gui_time.on_update
        def _(_: Any) -> None:
            if not self._updating_gui:
                self.seek(float(self.gui_time.value))

        @self.gui_speed.on_update
        def _(_: Any) -> None:
            if not self._updating_gui:
                self.set_speed(float(self.gui_speed.value))

    def _place_object(self, colour: str | None, shape: str | None, xy: np.ndarray, table_z: float) -> None:
        for handle in self.objects.values():
            handle.remove()
        self.objects = {}
        if shape is None:
            return
        rgb = colour_rgb(colour) if colour else (150, 150, 150)
        scene = self.server.scene
        x, y = float(xy[0]), float(xy[1])
        if shape == "apple":
            self.objects["body"] = scene.add_icosphere(
                "/object/body",
                radius=0.03,
                color=rgb,
                scale=(1.0, 1.0, 0.9),
                position=(x, y, table_z + 0.027),
            )
            self.objects["stem"] = scene.add_box(
                "/object/stem",
                color=(90, 60, 30),
                dimensions=(0.005, 0.005, 0.02),
                position=(x, y, table_z + 0.06),
            )
        elif shape == "banana":
            ts = np.linspace(-1.0, 1.0, 7)
            for k, s in enumerate(ts):
                self.objects[f"seg{k}"] = scene.add_icosphere(
                    f"/object/seg{k}",
                    radius=0.017 * (1.0 - 0.35 * s * s),
                    color=rgb,
                    position=(x + 0.025 * (1 - s * s), y + 0.06 * s, table_z + 0.015),
                )
        elif shape == "dice":
            self.objects["body"] = scene.add_box(
                "/object/body", color=rgb, dimensions=(0.045, 0.045, 0.045), position=(x, y, table_z + 0.0225)
            )
        else:  # phone
            self.objects["body"] = scene.add_box(
                "/object/body", color=rgb, dimensions=(0.075, 0.04, 0.012), position=(x, y, table_z + 0.006)
            )

    # recording and cursor
    def show(
        self, source: str, joints: np.ndarray, fps: float, colour: str | None = None, shape: str | None = None
    ) -> None:
        """Load a recording (joint angles [T,5], radians) and put the cursor at 0, paused."""
        joints = np.asarray(joints, dtype=float)
        keypoints = np.stack([np.stack([self._fk(q)[k] for k in KEYPOINTS]) for q in joints])
        hand = keypoints[:, 3]
        lowest = int(np.argmin(hand[:, 2]))
        table_z = TABLE_Z  # the scenario's table top (data.world), where the objects stand
        with self._lock, self.server.atomic():
            self._keypoints = keypoints
            for link, a, b in zip(self.links, keypoints[0, :-1], keypoints[0, 1:], strict=True):
                link.dimensions = (float(np.linalg.norm(b - a)), 0.03, 0.03)  # rigid links
            self._fps = float(fps)
            self.cursor = Cursor(
                source=source, t=0.0, duration_s=(len(joints) - 1) / fps, speed=self.cursor.speed
            )
            self.table.position = (float(hand[:, 0].mean()), float(hand[:, 1].mean()), table_z - 0.01)
            self.table.dimensions = (
                float(np.ptp(hand[:, 0])) + 0.25,
                float(np.ptp(hand[:, 1])) + 0.3,
                0.02,
            )
            self._place_object(colour, shape, hand[lowest, :2] + np.array([0.04, 0.0]), table_z)
            label = source if shape is None else f"{source} ({colour} {shape})"
            self.gui_title.content = f"**{label}**"
            self._apply()
        self._notify()

    def seek(self, t: float) -> None:
        with self._lock:
            self.cursor.t = float(np.clip(t, 0.0, self.cursor.duration_s))
            self._apply()
        self._notify()

    def play(self) -> None:
        with self._lock:
            if self.cursor.t >= self.cursor.duration_s:
                self.cursor.t = 0.0
            self.cursor.playing = self._keypoints is not None
        self._notify()

    def pause(self) -> None:
        with self._lock:
            self.cursor.playing = False
        self._notify()

    def set_speed(self, speed: float) -> None:
        with self._lock:
            self.cursor.speed = float(np.clip(speed, 0.05, 8.0))
        self._notify()

    def state(self) -> dict:
        with self._lock:
            return asdict(self.cursor)

    def _apply(self) -> None:
        """Move the arm to the cursor's time step and the 3D view's controls to the cursor."""
        if self._keypoints is None:
            return
        step = min(int(round(self.cursor.t * self._fps)), len(self._keypoints) - 1)
        kp = self._keypoints[step]
        for link, a, b in zip(self.links, kp[:-1], kp[1:], strict=True):
            link.position = tuple(float(v) for v in (a + b) / 2)
            link.wxyz = _x_to(b - a)
        for handle, p in zip(self.joints, kp, strict=True):
            handle.position = tuple(float(v) for v in p)
        self._updating_gui = True
        try:
            self.gui_time.max = max(self.cursor.duration_s, 0.05)
            self.gui_time.value = round(self.cursor.t, 2)
            self.gui_speed.value = self.cursor.speed
        finally:
            self._updating_gui = False

    # listeners (the page's WebSocket)
    def subscribe(self, listener: Callable[[dict], None]) -> Callable[[], None]:
        """Call `listener(state)` on every change; returns the function that unsubscribes."""
        with self._lock:
            self._listeners.append(listener)

        def unsubscribe() -> None:
            with self._lock:
                if listener in self._listeners:
                    self._listeners.remove(listener)

        return unsubscribe

    def _notify(self) -> None:
        state = self.state()
        with self._lock:
            listeners = list(self._listeners)
        for listener in listeners:
            listener(state)

    def _run(self) -> None:
        last = time.perf_counter()
        while not self._stop.wait(0.05):
            now = time.perf_counter()
            dt, last = now - last, now
            with self._lock:
                if not self.cursor.playing or self._keypoints is None:
                    continue
                t = self.cursor.t + dt * self.cursor.speed
                if t >= self.cursor.duration_s:
                    t = self.cursor.duration_s
                    self.cursor.playing = False
                self.cursor.t = t
                self._apply()
            self._notify()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=1.0)
        self.server.stop()
