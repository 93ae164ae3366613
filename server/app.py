"""The explorer app: FastAPI (REST + the web pages) and the viser 3D view, in one process.

`create_app(settings)` builds the app; its lifespan creates the services (`server.deps`: corpus,
model registry, Csc survey, describing, jobs) and starts the 3D viewer. Every module in
`server/routes/` that defines `router` is included, and every page module in `web/pages/` is
listed by `GET /api/pages` for the navigation: adding a resource or a page is adding a file.
A service's error (`server.services.errors`) becomes ``{"detail": message}`` with its status.
Every request first passes `server.guard.RequestGuard` (its own Host names, the access token, its
own Origin for state-changing requests and WebSockets, the JSON body limit).
"""

from __future__ import annotations

import importlib
import logging
import math
import pkgutil
import threading
from collections.abc import AsyncIterator, Callable, Sequence
from contextlib import asynccontextmanager
from pathlib import Path

import plotly
from fastapi import FastAPI, Request
from fastapi.encoders import jsonable_encoder
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles
from starlette.concurrency import run_in_threadpool

from data.nao import forward_kinematics
from data.recording import RecordingError
from server import routes
from server.deps import Services, build_services
from server.guard import RequestGuard
from server.jobs.kinds import warm_up_cosine
from server.jobs.manager import JobManager
from server.schemas.common import PageList
from server.services.corpus import Corpus
from server.services.errors import ServiceError
from server.settings import REPO_ROOT, Settings

logger = logging.getLogger(__name__)

PLOTLY_JS = Path(plotly.__file__).resolve().parent / "package_data" / "plotly.min.js"
# Pages that once had their own HTML and now are routes of the one web router (web/js/app.js).
MOVED_PAGES = {"/jobs.html": "jobs", "/results.html": "results", "/lessons/": "lessons"}
RECORDING_FORMAT = REPO_ROOT / "docs" / "recording-format.md"  # the format's full text, linked by Upload
CorpusLoader = Callable[[Settings], Corpus]


def _include_routers(app: FastAPI, names: Sequence[str] | None) -> None:
    for info in sorted(pkgutil.iter_modules(routes.__path__), key=lambda m: m.name):
        if names is not None and info.name not in names:
            continue
        module = importlib.import_module(f"server.routes.{info.name}")
        router = getattr(module, "router", None)
        if router is not None:
            app.include_router(router)


def _start(settings: Settings, load_corpus: CorpusLoader) -> Services:
    services = build_services(settings, load_corpus(settings))
    if settings.viser:
        from server.viewer import ViewerPool

        services.viewer = ViewerPool(forward_kinematics)
    logger.info("corpus: %d recordings; model %r", len(services.corpus.entries), services.models.served.name)
    return services


def _lifespan(settings: Settings, load_corpus: CorpusLoader, full: bool) -> Callable:
    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        services = await run_in_threadpool(_start, settings, load_corpus) if full else None
        # marks jobs a previous server left unfinished as interrupted
        jobs = services.jobs if services is not None else JobManager(settings)
        app.state.services, app.state.jobs = services, jobs
        if services is not None:
            warm_up_cosine()
            # The Csc spaces need every corpus recording described once: do it before anyone asks.
            threading.Thread(target=services.survey.warm_up, name="csc-warmup", daemon=True).start()
        try:
            yield
        finally:
            jobs.shutdown()
            if services is not None and services.viewer is not None:
                services.viewer.close()

    return lifespan


def _answer_errors(app: FastAPI) -> None:
    @app.exception_handler(ServiceError)
    async def service_error(request: Request, exc: ServiceError) -> JSONResponse:
        return JSONResponse({"detail": str(exc)}, status_code=exc.status)

    @app.exception_handler(RecordingError)
    async def recording_error(request: Request, exc: RecordingError) -> JSONResponse:
        return JSONResponse({"detail": str(exc)}, status_code=400)

    @app.exception_handler(RequestValidationError)
    async def invalid_request(request: Request, exc: RequestValidationError) -> JSONResponse:
        # FastAPI's own answer echoes the input: a NaN sent in a JSON body would make it a 500
        return JSONResponse({"detail": _finite(jsonable_encoder(exc.errors()))}, status_code=422)


def _finite(value: object) -> object:
    """`value` with every NaN or infinity (which JSON cannot carry) written as a string."""
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def _redirect_to(route: str) -> Callable[[], RedirectResponse]:
    def redirect() -> RedirectResponse:
        return RedirectResponse(f"/#/{route}", status_code=301)

    return redirect


def create_app(
    settings: Settings | None = None,
    load_corpus: CorpusLoader = Corpus.load,
    routers: Sequence[str] | None = None,
) -> FastAPI:
    """The ASGI app over the corpus `load_corpus(settings)` gives (default: the settings' corpus file).

    `routers` names the modules of `server/routes/` to include (default: all); an app of the
    jobs and results routers alone loads no corpus and no model."""
    settings = settings or Settings.from_env()
    full = routers is None or any(name not in ("jobs", "results") for name in routers)
    app = FastAPI(
        title="MultiMTRNN explorer",
        description="Describe NAO recordings with the multi-modal MTRNN (Heinrich & Wermter 2018) "
        "and explore its Csc spaces.",
        version="1.0",
        lifespan=_lifespan(settings, load_corpus, full),
    )
    app.state.settings = settings
    app.add_middleware(RequestGuard, settings=settings)  # Host, token, Origin, JSON size
    _include_routers(app, routers)
    _answer_errors(app)

    @app.get("/api/pages", response_model=PageList, tags=["pages"])
    def pages() -> PageList:
        """Page modules of the web app (web/pages/*.js), in file-name order."""
        return PageList(pages=sorted(p.stem for p in (settings.web_dir / "pages").glob("*.js")))

    @app.get("/vendor/plotly.min.js", include_in_schema=False)
    def plotly_js() -> FileResponse:
        return FileResponse(
            PLOTLY_JS, media_type="text/javascript", headers={"Cache-Control": "max-age=86400"}
        )

    @app.get("/docs/recording-format.md", include_in_schema=False)
    def recording_format() -> FileResponse:
        return FileResponse(RECORDING_FORMAT, media_type="text/markdown; charset=utf-8")

    for old, route in MOVED_PAGES.items():
        app.add_api_route(old, _redirect_to(route), include_in_schema=False)
    app.mount("/", StaticFiles(directory=settings.web_dir, html=True), name="web")
    return app
