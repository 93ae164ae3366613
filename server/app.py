"""The explorer app: FastAPI (REST + the web pages) and the viser 3D view, in one process.

`create_app(settings)` builds the app; its lifespan loads the corpus and the served model into an
`AppState` (injected into the routes with `Depends(get_state)`) and starts the 3D viewer. Every
module in `server/routes/` that defines `router` is included, and every page module in
`web/pages/` is listed by `GET /api/pages` for the navigation: adding a resource or a page is
adding a file.
"""

from __future__ import annotations

import importlib
import logging
import pkgutil
import threading
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from pathlib import Path

import plotly
from fastapi import FastAPI
from fastapi.responses import FileResponse
from fastapi.staticfiles import StaticFiles
from starlette.concurrency import run_in_threadpool

from server import routes
from server.routes.jobs import attach_jobs
from server.schemas import PageList
from server.settings import Settings
from server.state import AppState

logger = logging.getLogger(__name__)

PLOTLY_JS = Path(plotly.__file__).resolve().parent / "package_data" / "plotly.min.js"


def _include_routers(app: FastAPI) -> None:
    for info in sorted(pkgutil.iter_modules(routes.__path__), key=lambda m: m.name):
        module = importlib.import_module(f"server.routes.{info.name}")
        router = getattr(module, "router", None)
        if router is not None:
            app.include_router(router)


def create_app(
    settings: Settings | None = None, make_state: Callable[[Settings], AppState] | None = None
) -> FastAPI:
    """The ASGI app. `make_state` builds the AppState (default: the shipped corpus and models)."""
    settings = settings or Settings.from_env()
    make_state = make_state or AppState

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        state = await run_in_threadpool(make_state, settings)
        if settings.viser:
            from server.viewer import SceneViewer

            state.viewer = SceneViewer(state.backend.forward_kinematics)
        app.state.mtrnn = state
        jobs = attach_jobs(app, settings)  # marks jobs a previous server left unfinished as interrupted
        # The Csc spaces need every corpus recording described once: do it before anyone asks.
        threading.Thread(target=state.csc_cache, name="csc-warmup", daemon=True).start()
        try:
            yield
        finally:
            jobs.shutdown()
            if state.viewer is not None:
                state.viewer.close()

    app = FastAPI(
        title="MultiMTRNN explorer",
        description="Describe NAO recordings with the multi-modal MTRNN (Heinrich & Wermter 2018) "
        "and explore its Csc spaces.",
        version="1.0",
        lifespan=lifespan,
    )
    _include_routers(app)

    @app.get("/api/pages", response_model=PageList, tags=["pages"])
    def pages() -> PageList:
        """Page modules of the web app (web/pages/*.js), in file-name order."""
        return PageList(pages=sorted(p.stem for p in (settings.web_dir / "pages").glob("*.js")))

    @app.get("/vendor/plotly.min.js", include_in_schema=False)
    def plotly_js() -> FileResponse:
        return FileResponse(
            PLOTLY_JS, media_type="text/javascript", headers={"Cache-Control": "max-age=86400"}
        )

    app.mount("/", StaticFiles(directory=settings.web_dir, html=True), name="web")
    return app
