"""Training and evaluation jobs and their live progress (Server-Sent Events).

    GET    /api/jobs                   every job (newest first), also those of earlier server runs
    POST   /api/jobs                   start one: {"kind": "train", "mode": "end_to_end", "fold": 0, ...}
    GET    /api/jobs/{id}              one job, with its latest progress
    GET    /api/jobs/{id}/events       text/event-stream: snapshot, progress (epoch, loss, Csc PCA
                                       points), run, done / error / cancelled
    POST   /api/jobs/{id}/cancel       kill it

A finished training job's model joins the app's model registry (`/api/models` lists it, and
`PUT /api/models/selected` serves it; after a restart the app finds it in the models folder).
The `JobManager` lives on `app.state.jobs`; it is created on first use when the app's lifespan
did not create it (`server.routes.jobs.attach_jobs(app, settings)` does it at start-up).
"""

from __future__ import annotations

import asyncio
import json
import os
import threading
from pathlib import Path
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, FastAPI, HTTPException, Request
from fastapi.responses import StreamingResponse
from pydantic import BaseModel, Field
from starlette.concurrency import run_in_threadpool

from server.jobs import JobManager
from server.settings import REPO_ROOT, Settings

router = APIRouter(tags=["jobs"])
_create_lock = threading.Lock()


class JobRequest(BaseModel):
    kind: Literal["train", "evaluate"]
    mode: str = Field(description="faithful or end_to_end (train); also peer (evaluate)")
    fold: int = Field(0, ge=0, description="train: the 50:50 scene split")
    seed: int = Field(0, ge=0, description="train: initialisation seed; evaluate: base seed")
    folds: int = Field(2, ge=1, le=10, description="evaluate: K")
    inits: int = Field(1, ge=1, le=10, description="evaluate: N")
    workers: int = Field(1, ge=1, le=8, description="evaluate: local worker processes")
    name: str | None = Field(None, description="train: model folder name (default: mode-fold-seed-id)")
    overrides: dict[str, Any] = Field(
        default_factory=dict, description='e.g. {"training.epochs_auditory": 200}'
    )


class Job(BaseModel):
    id: str
    kind: str
    params: dict
    status: str = Field(description="queued, running, done, failed, cancelled, interrupted")
    created: float
    updated: float
    progress: dict | None = None
    result: dict | None = None
    error: str | None = None


def run_dir() -> Path:
    """The run store of the app's jobs: $MTRNN_RUN_DIR or runs/ (the CLI's default too)."""
    return Path(os.environ.get("MTRNN_RUN_DIR", REPO_ROOT / "runs"))


def _register_model(app: FastAPI, name: str, path: Path) -> None:
    """A finished model joins the app's model registry (listed by /api/models, selectable)."""
    state = getattr(app.state, "mtrnn", None)
    if state is not None:
        state.model_dirs[name] = path


def attach_jobs(app: FastAPI, settings: Settings) -> JobManager:
    """Create the app's JobManager (marks jobs of a previous run that never finished interrupted)."""
    corpus = str(settings.corpus_path) if settings.corpus_path else None
    jobs = JobManager(
        run_dir(), settings.models_dir, data_arg=corpus, on_model=lambda n, p: _register_model(app, n, p)
    )
    app.state.jobs = jobs
    return jobs


def get_jobs(request: Request) -> JobManager:
    app = request.app
    with _create_lock:
        jobs = getattr(app.state, "jobs", None)
        if jobs is None:
            state = getattr(app.state, "mtrnn", None)
            settings = state.settings if state is not None else Settings.from_env()
            jobs = attach_jobs(app, settings)
    return jobs


Jobs = Annotated[JobManager, Depends(get_jobs)]


def _job(jobs: JobManager, job_id: str) -> dict:
    job = jobs.get(job_id)
    if job is None:
        raise HTTPException(404, f"no job {job_id!r}")
    return job


@router.get("/api/jobs", response_model=list[Job])
def list_jobs(jobs: Jobs) -> list[dict]:
    return jobs.list()


@router.post("/api/jobs", response_model=Job, status_code=201)
async def start_job(body: JobRequest, jobs: Jobs) -> dict:
    """Start a training job (one model, saved to the models folder) or an evaluation (K x N runs)."""
    params = body.model_dump(exclude={"kind"})
    if body.kind == "train":
        for key in ("folds", "inits", "workers"):
            params.pop(key)
    else:
        for key in ("fold", "name"):
            params.pop(key)
    try:
        return await run_in_threadpool(jobs.start, body.kind, params)
    except ValueError as err:
        raise HTTPException(422, str(err)) from None


@router.get("/api/jobs/{job_id}", response_model=Job)
def get_job(job_id: str, jobs: Jobs) -> dict:
    return _job(jobs, job_id)


@router.post("/api/jobs/{job_id}/cancel", response_model=Job)
def cancel_job(job_id: str, jobs: Jobs) -> dict:
    job = _job(jobs, job_id)
    if not jobs.cancel(job_id):
        raise HTTPException(409, f"job {job_id} is not running (status {job['status']})")
    return _job(jobs, job_id)


def _sse(event: dict) -> str:
    return f"event: {event.get('type', 'message')}\ndata: {json.dumps(event)}\n\n"


@router.get("/api/jobs/{job_id}/events")
async def job_events(job_id: str, request: Request, jobs: Jobs) -> StreamingResponse:
    """Server-Sent Events: a snapshot of the job, then every event until it ends."""
    _job(jobs, job_id)
    loop = asyncio.get_running_loop()
    events: asyncio.Queue = asyncio.Queue()
    sub = jobs.subscribe(job_id, lambda e: loop.call_soon_threadsafe(events.put_nowait, e))

    async def stream():
        try:
            yield _sse({"type": "snapshot", "job": _job(jobs, job_id)})
            if not jobs.is_running(job_id):
                return
            while not await request.is_disconnected():
                try:
                    event = await asyncio.wait_for(events.get(), timeout=15.0)
                except TimeoutError:
                    yield ": keep-alive\n\n"
                    continue
                yield _sse(event)
                if event["type"] in ("done", "error", "cancelled"):
                    return
        finally:
            jobs.unsubscribe(sub)

    return StreamingResponse(
        stream(),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
    )
