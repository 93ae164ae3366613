"""Training and evaluation jobs and their live progress (Server-Sent Events).

    GET    /api/jobs                   every job (newest first), also those of earlier server runs
    POST   /api/jobs                   start one: {"kind": "train", "mode": "end_to_end", "fold": 0, ...}
    GET    /api/jobs/{id}              one job, with its latest progress
    GET    /api/jobs/{id}/events       text/event-stream: snapshot, progress (epoch, loss, Csc PCA
                                       points), run, done / error / cancelled
    POST   /api/jobs/{id}/cancel       kill it

A finished training job's model joins the app's model registry (`/api/models` lists it, and
`PUT /api/models/selected` serves it; after a restart the app finds it in the models folder).
The jobs are the app's `JobManager` (server.jobs.manager), created in the lifespan.
"""

from __future__ import annotations

import asyncio
import json

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import StreamingResponse
from starlette.concurrency import run_in_threadpool

from server.deps import JobsDep
from server.jobs.manager import JobManager
from server.schemas.jobs import Job, JobRequest

router = APIRouter(tags=["jobs"])


def _job(jobs: JobManager, job_id: str) -> dict:
    job = jobs.get(job_id)
    if job is None:
        raise HTTPException(404, f"no job {job_id!r}")
    return job


@router.get("/api/jobs", response_model=list[Job])
def list_jobs(jobs: JobsDep) -> list[dict]:
    return jobs.list()


@router.post("/api/jobs", response_model=Job, status_code=201)
async def start_job(body: JobRequest, jobs: JobsDep) -> dict:
    """Start a training job (one model, saved to the models folder) or an evaluation (K x N runs)."""
    params = body.model_dump(exclude={"kind"})
    if body.kind == "train":
        for key in ("folds", "inits", "workers"):
            params.pop(key)
    else:
        for key in ("fold", "name"):
            params.pop(key)
    return await run_in_threadpool(jobs.start, body.kind, params)


@router.get("/api/jobs/{job_id}", response_model=Job)
def get_job(job_id: str, jobs: JobsDep) -> dict:
    return _job(jobs, job_id)


@router.post("/api/jobs/{job_id}/cancel", response_model=Job)
def cancel_job(job_id: str, jobs: JobsDep) -> dict:
    job = _job(jobs, job_id)
    if not jobs.cancel(job_id):
        raise HTTPException(409, f"job {job_id} is not running (status {job['status']})")
    return _job(jobs, job_id)


def _sse(event: dict) -> str:
    return f"event: {event.get('type', 'message')}\ndata: {json.dumps(event)}\n\n"


@router.get("/api/jobs/{job_id}/events")
async def job_events(job_id: str, request: Request, jobs: JobsDep) -> StreamingResponse:
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
