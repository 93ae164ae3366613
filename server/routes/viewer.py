"""The 3D viewer: its shared time cursor (GET/POST /api/viewer, WS /api/viewer/ws) and viser's client,
served on the app's origin (GET /viser/) with its WebSocket proxied (WS /viser).

The proxy passes viser's messages to the client unchanged, and from the client only the ones the
page needs (`CLIENT_MESSAGES`: its camera); everything else a client could send viser (GUI
values, a share-URL request that would open a public tunnel, file uploads) is dropped. viser
frames each client message as one msgpack map whose ``type`` names its message class
(`viser.infra._messages.Message.deserialize`). Only the app's own pages reach the proxy
(`server.guard` checks the Origin of every WebSocket).
"""

from __future__ import annotations

import asyncio
import contextlib
from pathlib import Path

import msgspec
import viser
import websockets
from fastapi import APIRouter, HTTPException, Request, WebSocket, WebSocketDisconnect
from fastapi.responses import FileResponse
from pydantic import ValidationError
from starlette.concurrency import run_in_threadpool

from data.scenario import scene_from_utterance
from data.world import FPS
from server.deps import Services, ServicesDep, services_of
from server.schemas.common import Problem
from server.schemas.viewer import ViewerCommand, ViewerState
from server.services.errors import ServiceError, Unavailable
from server.viewer import SceneViewer

router = APIRouter(tags=["viewer"])

VISER_CLIENT = Path(viser.__file__).resolve().parent / "client" / "build" / "index.html"
CLIENT_MESSAGES = frozenset({"ViewerCameraMessage"})  # what the page's 3D view sends viser
MAX_CLIENT_MESSAGE = 16 * 1024  # a camera message is ~300 bytes


def _viewer(services: Services) -> SceneViewer:
    if services.viewer is None:
        raise Unavailable("the 3D viewer is not running (started with MTRNN_VISER=0)")
    return services.viewer


def _state(services: Services) -> ViewerState:
    if services.viewer is None:
        return ViewerState(available=False, source=None, t=0.0, duration_s=0.0, playing=False, speed=1.0)
    return ViewerState(available=True, **services.viewer.state())


def show(services: Services, source: str) -> None:
    """Load a corpus recording or an upload into the 3D view (recordings are at data.world.FPS)."""
    viewer = _viewer(services)
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
def get_viewer(services: ServicesDep) -> ViewerState:
    """Where the shared time cursor is."""
    return _state(services)


@router.post(
    "/api/viewer", response_model=ViewerState, responses={404: {"model": Problem}, 503: {"model": Problem}}
)
async def command_viewer(services: ServicesDep, cmd: ViewerCommand) -> ViewerState:
    """Show a recording, move the cursor, play, pause or change the speed."""
    viewer = _viewer(services)
    if cmd.show is not None and cmd.show != viewer.cursor.source:
        await run_in_threadpool(show, services, cmd.show)
    if cmd.speed is not None:
        viewer.set_speed(cmd.speed)
    if cmd.t is not None:
        viewer.seek(cmd.t)
    if cmd.playing is True:
        viewer.play()
    elif cmd.playing is False:
        viewer.pause()
    return _state(services)


async def _command(ws: WebSocket, services: Services, text: str) -> None:
    """Run one command of the page's WebSocket; a bad one is answered ``{"detail": ...}``."""
    try:
        await command_viewer(services, ViewerCommand.model_validate_json(text))
    except ValidationError as exc:
        await ws.send_json({"detail": "; ".join(e["msg"] for e in exc.errors())})
    except (ValueError, ServiceError, HTTPException) as exc:
        await ws.send_json({"detail": str(getattr(exc, "detail", exc))})


@router.websocket("/api/viewer/ws")
async def viewer_socket(ws: WebSocket) -> None:
    """Pushes the cursor on every change; accepts the same commands as POST /api/viewer."""
    services = services_of(ws)
    await ws.accept()
    if services.viewer is None:
        await ws.send_json(_state(services).model_dump())
        await ws.close()
        return
    loop = asyncio.get_running_loop()
    queue: asyncio.Queue[dict] = asyncio.Queue(maxsize=64)

    def push(cursor: dict) -> None:
        loop.call_soon_threadsafe(lambda: queue.full() or queue.put_nowait(cursor))

    unsubscribe = services.viewer.subscribe(push)

    async def sender() -> None:
        await ws.send_json(_state(services).model_dump())
        while True:
            cursor = await queue.get()
            while not queue.empty():  # only the newest matters
                cursor = queue.get_nowait()
            await ws.send_json({"available": True, **cursor})

    task = asyncio.create_task(sender())
    try:
        while True:
            await _command(ws, services, await ws.receive_text())
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


@router.get("/viser/", include_in_schema=False)
def viser_client(request: Request) -> FileResponse:
    """viser's web client (one file); it connects back to ws://<this origin>/viser."""
    _viewer(services_of(request))
    return FileResponse(VISER_CLIENT, media_type="text/html")


@router.websocket("/viser")
async def viser_proxy(ws: WebSocket) -> None:
    """Relay the viser client's WebSocket to the viser server on 127.0.0.1, keeping its subprotocol."""
    viewer = services_of(ws).viewer
    if viewer is None:
        await ws.close(code=1011)
        return
    offered = ws.scope.get("subprotocols") or []
    try:
        upstream = await websockets.connect(
            f"ws://127.0.0.1:{viewer.port}",
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
