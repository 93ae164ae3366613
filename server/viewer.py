"""The 3D scene (viser): the NAO's right arm replaying a recording over a table and its object.

`SceneViewer` owns its viser server and every handle it adds. The arm is drawn from primitives
placed by `data.nao.forward_kinematics` (links as boxes, joints as spheres), the
same chain as the URDF. The web page owns the controls (play, time, speed): `show(...)` loads a
recording, `seek(t)`, `play()`, `pause()`, `set_speed(x)` move the time cursor (finite values only,
`ValueError` otherwise), and every change is sent to the listeners (the page's WebSocket) so the
camera frame, the plots and the phoneme being produced follow it. viser's own panel holds only the
name of the recording shown: it has no control a client could change for the others.

Each page load has its own view (`ViewerPool`): a `SceneViewer` with its own viser server and cursor,
so one client's actions never change what another sees; two pages with the same view id share it on
purpose. The pool keeps at most `MAX_VIEWS` live (~0.7 MB and ~43 ms to start one): a new view
replaces the least recently used one nobody holds, and is refused (`Unavailable`, 503) when all are held.

    >>> views = ViewerPool(forward_kinematics)            # doctest: +SKIP
    >>> viewer = views.acquire("Xy3_k")
    >>> viewer.show("slide-red-apple-2", joints, FPS, "red", "apple")
    >>> viewer.seek(1.5); viewer.play(); views.release("Xy3_k")
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import socket
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import viser

from data.world import FPS, OBJECT_SIZE, TABLE_Z, colour_rgb
from server.services.errors import Unavailable

logger = logging.getLogger(__name__)

ARM_RGB = (225, 225, 230)
JOINT_RGB = (90, 95, 110)
TABLE_RGB = (170, 130, 90)
KEYPOINTS = ("shoulder", "elbow", "wrist", "hand")
CAMERA_DIRECTION = np.array([0.55, -0.75, 0.45])  # from the scene's centre, front right and above
SPEEDS = (0.05, 8.0)  # slowest and fastest replay
MAX_VIEWS = 8  # live views (a viser server each)


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
    """The time cursor of one view."""

    source: str | None = None
    t: float = 0.0
    duration_s: float = 0.0
    playing: bool = False
    speed: float = 1.0


class SceneViewer:
    """A viser server on 127.0.0.1 showing one recording at a time, with play / pause / scrub / speed."""

    def __init__(self, forward_kinematics: Callable[[np.ndarray], dict[str, np.ndarray]]) -> None:
        self._fk = forward_kinematics
        # viser prints a banner and its websockets server logs its own address: the app's URL is the
        # one to open (viser is reached through the app's /viser proxy)
        logging.getLogger("websockets.server").setLevel(logging.WARNING)
        with _quiet():
            self.server = viser.ViserServer(
                host="127.0.0.1", port=free_port(), label="MultiMTRNN", verbose=False
            )
        self.port = self.server.get_port()  # viser moves on silently if the port was taken meanwhile
        self.cursor = Cursor()
        self._lock = threading.RLock()
        self._keypoints: np.ndarray | None = None  # [T, 4, 3]
        self._fps = FPS
        self._listeners: list[Callable[[dict], None]] = []
        self._build_scene()
        self._build_gui()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="viewer-playback", daemon=True)
        self._thread.start()
        logger.debug("3D viewer (viser) on 127.0.0.1:%d, reached through the app's /viser", self.port)

    # scene
    def _build_scene(self) -> None:
        scene = self.server.scene
        scene.set_up_direction("+z")
        self.server.initial_camera.position = (0.42, -0.55, 0.3)
        self.server.initial_camera.look_at = (0.18, -0.08, 0.02)
        self.server.gui.configure_theme(
            control_layout="floating", control_width="small", show_logo=False, show_share_button=False
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
        self.gui_title = self.server.gui.add_markdown("**No recording loaded.**")

    def _place_object(self, colour: str | None, shape: str | None, xy: np.ndarray) -> None:
        """The object on the table at `xy`, in the scenario's size (data.world.OBJECT_SIZE) and colour."""
        for handle in self.objects.values():
            handle.remove()
        self.objects = {}
        if shape is None:
            return
        rgb = colour_rgb(colour) if colour else (150, 150, 150)
        scene = self.server.scene
        x, y = float(xy[0]), float(xy[1])
        half_x, half_y, height = OBJECT_SIZE[shape]
        if shape == "apple":
            self.objects["body"] = scene.add_icosphere(
                "/object/body",
                radius=half_x,
                color=rgb,
                scale=(1.0, 1.0, height / (2 * half_x)),
                position=(x, y, TABLE_Z + height / 2),
            )
            self.objects["stem"] = scene.add_box(
                "/object/stem",
                color=(90, 60, 30),
                dimensions=(0.005, 0.005, 0.02),
                position=(x, y, TABLE_Z + height + 0.008),
            )
        elif shape == "banana":  # lies across the table: long along y, bent towards +x
            for k, s in enumerate(np.linspace(-1.0, 1.0, 7)):
                self.objects[f"seg{k}"] = scene.add_icosphere(
                    f"/object/seg{k}",
                    radius=half_x * (1.0 - 0.35 * s * s),
                    color=rgb,
                    position=(x + half_x * (1 - s * s), y + (half_y - half_x) * s, TABLE_Z + height / 2),
                )
        else:  # dice and phone: boxes
            self.objects["body"] = scene.add_box(
                "/object/body",
                color=rgb,
                dimensions=(2 * half_x, 2 * half_y, height),
                position=(x, y, TABLE_Z + height / 2),
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
        with self._lock, self.server.atomic():
            self._keypoints = keypoints
            for link, a, b in zip(self.links, keypoints[0, :-1], keypoints[0, 1:], strict=True):
                link.dimensions = (float(np.linalg.norm(b - a)), 0.03, 0.03)  # rigid links
            self._fps = float(fps)
            self.cursor = Cursor(
                source=source, t=0.0, duration_s=(len(joints) - 1) / fps, speed=self.cursor.speed
            )
            self.table.position = (float(hand[:, 0].mean()), float(hand[:, 1].mean()), TABLE_Z - 0.01)
            self.table.dimensions = (
                float(np.ptp(hand[:, 0])) + 0.25,
                float(np.ptp(hand[:, 1])) + 0.3,
                0.02,
            )
            object_xy = hand[lowest, :2] + np.array([0.04, 0.0])
            self._place_object(colour, shape, object_xy)
            self._frame(np.vstack([keypoints.reshape(-1, 3), [[*object_xy, TABLE_Z]], self._table_corners()]))
            label = source if shape is None else f"{source} ({colour} {shape})"
            self.gui_title.content = f"**{label}**"
            self._apply()
        self._notify()

    def _table_corners(self) -> np.ndarray:
        centre, size = np.asarray(self.table.position), np.asarray(self.table.dimensions)
        return np.array([centre + size * (sx, sy, 0) / 2 for sx in (-1, 1) for sy in (-1, 1)])

    def _frame(self, points: np.ndarray) -> None:
        """Point every camera (new clients' and the open ones') at the box around `points`: the
        arm over the whole recording, the table and the object."""
        low, high = points.min(axis=0), points.max(axis=0)
        centre, radius = (low + high) / 2, float(np.linalg.norm(high - low)) / 2
        position = centre + CAMERA_DIRECTION / np.linalg.norm(CAMERA_DIRECTION) * radius * 1.8
        cameras = [self.server.initial_camera, *(c.camera for c in self.server.get_clients().values())]
        for camera in cameras:
            camera.position = tuple(float(v) for v in position)
            camera.look_at = tuple(float(v) for v in centre)

    def seek(self, t: float) -> None:
        """Move the cursor to `t` seconds (clamped to the recording)."""
        t = _finite(t, "the time")
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
        """Replay at `speed` times real time (clamped to `SPEEDS`)."""
        speed = _finite(speed, "the speed")
        with self._lock:
            self.cursor.speed = float(np.clip(speed, *SPEEDS))
        self._notify()

    def state(self) -> dict:
        with self._lock:
            return asdict(self.cursor)

    def _apply(self) -> None:
        """Move the arm to the cursor's time step."""
        if self._keypoints is None:
            return
        step = min(int(round(self.cursor.t * self._fps)), len(self._keypoints) - 1)
        kp = self._keypoints[step]
        for link, a, b in zip(self.links, kp[:-1], kp[1:], strict=True):
            link.position = tuple(float(v) for v in (a + b) / 2)
            link.wxyz = _x_to(b - a)
        for handle, p in zip(self.joints, kp, strict=True):
            handle.position = tuple(float(v) for v in p)

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
        with _quiet():
            self.server.stop()


class ViewerPool:
    """At most `size` live views by id, a `SceneViewer` each. A view is held (`acquire` .. `release`)
    while a request or a socket uses it; only views nobody holds are replaced, least recently used first."""

    def __init__(
        self, forward_kinematics: Callable[[np.ndarray], dict[str, np.ndarray]], size: int = MAX_VIEWS
    ) -> None:
        self._fk = forward_kinematics
        self.size = size
        self._views: OrderedDict[str, SceneViewer] = OrderedDict()  # least recently used first
        self._holds: dict[str, int] = {}
        self._lock = threading.Lock()

    def get(self, view: str) -> SceneViewer | None:
        """The live view `view`, or None (nothing is started)."""
        with self._lock:
            return self._views.get(view)

    def acquire(self, view: str) -> SceneViewer:
        """The view `view` (started when new), held until `release(view)`."""
        evicted = None
        with self._lock:
            viewer = self._views.get(view)
            if viewer is None:
                if len(self._views) >= self.size:
                    idle = next((v for v in self._views if not self._holds.get(v)), None)
                    if idle is None:
                        raise Unavailable(f"all {self.size} 3D views are in use by open pages: close one")
                    evicted = self._views.pop(idle)
                viewer = self._views[view] = SceneViewer(self._fk)
            self._views.move_to_end(view)
            self._holds[view] = self._holds.get(view, 0) + 1
        if evicted is not None:
            evicted.close()
        return viewer

    def release(self, view: str) -> None:
        with self._lock:
            held = self._holds.get(view, 0) - 1
            if held > 0:
                self._holds[view] = held
            else:
                self._holds.pop(view, None)

    def views(self) -> list[str]:
        """The live view ids, least recently used first."""
        with self._lock:
            return list(self._views)

    def close(self) -> None:
        with self._lock:
            viewers, self._views = list(self._views.values()), OrderedDict()
        for viewer in viewers:
            viewer.close()


def _finite(value: float, what: str) -> float:
    """`value` as a float, or ValueError when it is not a finite number (NaN would stop playback)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number):
        raise ValueError(f"{what} must be a finite number, not {value!r}")
    return number


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """Keep viser's console output (its banner, "Server stopped") out of the app's console."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield
