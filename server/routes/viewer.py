"""The 3D views: each page's time cursor (GET/POST /api/viewer?view=, WS /api/viewer/ws?view=) and
viser's client for its view, served on the app's origin (GET /viser/<view>/) with its WebSocket
proxied (WS /viser/<view>: viser's client connects to its own URL minus the query and the last "/").

A view is a page load's own `SceneViewer` in the `ViewerPool` (`server.viewer`), named by the id the
page makes (`web/js/cursor.js`); pages that give the same id share it on purpose. The proxy passes
viser's messages to the client unchanged, and from the client only the ones the page needs
(`CLIENT_MESSAGES`: its camera); everything else a client could send viser (GUI values, a share-URL
request that would open a public tunnel, file uploads) is dropped. viser frames each client message
as one msgpack map whose ``type`` names its message class (`viser.infra._messages.Message.deserialize`).
Only the app's own pages reach the proxy (`server.guard` checks the Origin of every WebSocket).
"""

from __future__ import annotations

import asyncio
import contextlib
from dataclasses import asdict
from pathlib import Path
from typing import Annotated

import msgspec
import viser
import websockets
from fastapi import APIRouter, HTTPException, Query, Request, WebSocket, WebSocketDisconnect
from fastapi import Path as PathParam
from fastapi.responses import FileResponse
from pydantic import ValidationError
from starlette.concurrency import run_in_threadpool

from data.scenario import scene_from_utterance
from data.world import FPS
from server.deps import Services, ServicesDep, services_of
from server.schemas.common import Problem
from server.schemas.viewer import VIEW_ID, ViewerCommand, ViewerState
from server.services.errors import ServiceError, Unavailable
from server.viewer import Cursor, SceneViewer, ViewerPool

router = APIRouter(tags=["viewer"])

VISER_CLIENT = Path(viser.__file__).resolve().parent / "client" / "build" / "index.html"
CLIENT_MESSAGES = frozenset({"ViewerCameraMessage"})  # what the page's 3D view sends viser
MAX_CLIENT_MESSAGE = 16 * 1024  # a camera message is ~300 bytes


ViewId = Annotated[str, Query(pattern=VIEW_ID, description="the page's view id")]
NOT_RUNNING = "the 3D viewer is not running (started with MTRNN_VISER=0)"
BUSY = 1013  # WebSocket close code: try again later


def _pool(services: Services) -> ViewerPool:
    if services.viewer is None:
        raise Unavailable(NOT_RUNNING)
    return services.viewer


def _state(viewer: SceneViewer | None) -> ViewerState:
    return ViewerState(available=True, **(viewer.state() if viewer is not None else asdict(Cursor())))


UNAVAILABLE = ViewerState(available=False, source=None, t=0.0, duration_s=0.0, playing=False, speed=1.0)


def show(services: Services, viewer: SceneViewer, source: str) -> None:
    """Load a corpus recording or an upload into a 3D view (recordings are at data.world.FPS)."""
    if source.startswith("upload-"):
        up = services.describe.upload(source)
        colour = shape = None
        if up.result.expected:
            with contextlib.suppress(ValueError):
                scene = scene_from_utterance(up.result.expected)
                colour, shape = scene.colour, scene.shape
        viewer.show(source, up.recording.joints, FPS, colour, shape)
    else:
        entry = services.corpus.entry(source)
        viewer.show(source, entry.joints, FPS, entry.scene.colour, entry.scene.shape)


@router.get("/api/viewer", response_model=ViewerState)
def get_viewer(
    services: ServicesDep, view: Annotated[str | None, Query(pattern=VIEW_ID)] = None
) -> ViewerState:
    """Whether the 3D viewer runs, and where the cursor of `view` is (nothing is started)."""
    if services.viewer is None:
        return UNAVAILABLE
    return _state(services.viewer.get(view) if view else None)


@router.post(
    "/api/viewer", response_model=ViewerState, responses={404: {"model": Problem}, 503: {"model": Problem}}
)
async def command_viewer(services: ServicesDep, cmd: ViewerCommand, view: ViewId) -> ViewerState:
    """Show a recording in `view`, move its cursor, play, pause or change the speed."""
    pool = _pool(services)
    viewer = await run_in_threadpool(pool.acquire, view)
    try:
        return await _run(services, viewer, cmd)
    finally:
        pool.release(view)


async def _run(services: Services, viewer: SceneViewer, cmd: ViewerCommand) -> ViewerState:
    if cmd.show is not None and cmd.show != viewer.cursor.source:
        await run_in_threadpool(show, services, viewer, cmd.show)
    if cmd.speed is not None:
        viewer.set_speed(cmd.speed)
    if cmd.t is not None:
        viewer.seek(cmd.t)
    if cmd.playing is True:
        viewer.play()
    elif cmd.playing is False:
        viewer.pause()
    return _state(viewer)


async def _command(ws: WebSocket, services: Services, viewer: SceneViewer, text: str) -> None:
    """Run one command of the page's WebSocket; a bad one is answered ``{"detail": ...}``."""
    try:
        await _run(services, viewer, ViewerCommand.model_validate_json(text))
    except ValidationError as exc:
        await ws.send_json({"detail": "; ".join(e["msg"] for e in exc.errors())})
    except (ValueError, ServiceError, HTTPException) as exc:
        await ws.send_json({"detail": str(getattr(exc, "detail", exc))})


@router.websocket("/api/viewer/ws")
async def viewer_socket(ws: WebSocket, view: Annotated[str | None, Query(pattern=VIEW_ID)] = None) -> None:
    """Pushes the cursor of `view` on every change; accepts the same commands as POST /api/viewer."""
    services = services_of(ws)
    await ws.accept()
    if services.viewer is None:
        await ws.send_json(UNAVAILABLE.model_dump())
        await ws.close()
        return
    if view is None:
        await ws.send_json({"available": False, "detail": "which view? add ?view=<id> ([A-Za-z0-9_-]{1,32})"})
        await ws.close(code=1008)
        return
    try:
        viewer = await run_in_threadpool(services.viewer.acquire, view)
    except Unavailable as exc:
        await ws.send_json({"available": False, "detail": str(exc)})
        await ws.close(code=BUSY)
        return
    try:
        await _follow(ws, services, viewer)
    finally:
        services.viewer.release(view)


async def _follow(ws: WebSocket, services: Services, viewer: SceneViewer) -> None:
    loop = asyncio.get_running_loop()
    queue: asyncio.Queue[dict] = asyncio.Queue(maxsize=64)

    def push(cursor: dict) -> None:
        loop.call_soon_threadsafe(lambda: queue.full() or queue.put_nowait(cursor))

    unsubscribe = viewer.subscribe(push)

    async def sender() -> None:
        await ws.send_json(_state(viewer).model_dump())
        while True:
            cursor = await queue.get()
            while not queue.empty():  # only the newest matters
                cursor = queue.get_nowait()
            await ws.send_json({"available": True, **cursor})

    task = asyncio.create_task(sender())
    try:
        while True:
            await _command(ws, services, viewer, await ws.receive_text())
    except WebSocketDisconnect:
        pass
    finally:
        unsubscribe()
        task.cancel()


def passes(data: bytes) -> bool:
    """Whether a client's message to viser is one the page needs (`CLIENT_MESSAGES`)."""
    if len(data) > MAX_CLIENT_MESSAGE:
        return False
    try:
        message = msgspec.msgpack.decode(data)
    except msgspec.DecodeError:
        return False
    return isinstance(message, dict) and message.get("type") in CLIENT_MESSAGES


ViewPath = Annotated[str, PathParam(pattern=VIEW_ID)]


@router.get("/viser/{view}/", include_in_schema=False)
def viser_client(request: Request, view: ViewPath) -> FileResponse:
    """viser's web client (one file); it connects back to ws://<this origin>/viser/<view>."""
    _pool(services_of(request))
    return FileResponse(VISER_CLIENT, media_type="text/html")


@router.websocket("/viser/{view}")
async def viser_proxy(ws: WebSocket, view: ViewPath) -> None:
    """Relay the viser client's WebSocket to the viser server of `view` on 127.0.0.1."""
    pool = services_of(ws).viewer
    if pool is None:
        await ws.close(code=1011)
        return
    try:
        viewer = await run_in_threadpool(pool.acquire, view)
    except Unavailable:
        await ws.close(code=BUSY)
        return
    try:
        await _relay(ws, viewer.port)
    finally:
        pool.release(view)


async def _relay(ws: WebSocket, port: int) -> None:
    """Relay `ws` to the viser server on 127.0.0.1:`port`, keeping its subprotocol."""
    offered = ws.scope.get("subprotocols") or []
    try:
        upstream = await websockets.connect(
            f"ws://127.0.0.1:{port}",
            subprotocols=offered or None,  # e.g. "viser-v1.1.1": viser checks the client's version
            max_size=None,
            compression=None,
        )
    except OSError:
        await ws.close(code=1011)
        return
    await ws.accept(subprotocol=upstream.subprotocol)

    async def down() -> None:
        async for message in upstream:
            if isinstance(message, bytes):
                await ws.send_bytes(message)
            else:
                await ws.send_text(message)

    async def up() -> None:
        while True:
            message = await ws.receive()
            if message["type"] == "websocket.disconnect":
                return
            data = message.get("bytes")
            if data is not None and passes(data):
                await upstream.send(data)

    tasks = [asyncio.create_task(down()), asyncio.create_task(up())]
    try:
        await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in tasks:
            task.cancel()
        await upstream.close()
        with contextlib.suppress(RuntimeError, WebSocketDisconnect):
            await ws.close()
