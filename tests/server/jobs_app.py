"""A small app for the job tests: the jobs and results routers, web pages and Plotly, tiny scenes.

Run by uvicorn in a subprocess (`--factory jobs_app:create`) so a test can kill the server;
JOBS_RUN_DIR, JOBS_MODELS_DIR name the run store and models folder.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import FileResponse
from fastapi.staticfiles import StaticFiles

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "model"))  # tiny_data, importable by the spawned jobs too

from server.app import PLOTLY_JS  # noqa: E402
from server.jobs import JobManager  # noqa: E402
from server.routes import jobs, results  # noqa: E402
from server.settings import WEB_DIR  # noqa: E402

TINY_DATA = "tiny_data:tiny_sequence_set"


def create() -> FastAPI:
    app = FastAPI()
    app.include_router(jobs.router)
    app.include_router(results.router)
    app.state.jobs = JobManager(
        Path(os.environ["JOBS_RUN_DIR"]), Path(os.environ["JOBS_MODELS_DIR"]), data_loader=TINY_DATA
    )

    @app.get("/vendor/plotly.min.js")
    def plotly_js() -> FileResponse:
        return FileResponse(PLOTLY_JS, media_type="text/javascript")

    app.mount("/", StaticFiles(directory=WEB_DIR, html=True), name="web")
    return app
