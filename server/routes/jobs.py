"""Training and evaluation jobs and their live progress (Server-Sent Events).

    GET    /api/jobs                   every job (newest first), also those of earlier server runs
    GET    /api/jobs/presets           the epoch presets, each with its measured minutes per mode
    POST   /api/jobs                   queue one: {"kind": "train", "mode": "end_to_end", "fold": 0, ...};
                                       422 for a bad value (the message names it), 409 for a taken name
    GET    /api/jobs/{id}              one job, with its latest progress (or its queue position)
    GET    /api/jobs/{id}/events       text/event-stream: snapshot, progress (epoch, loss, attempt,
                                       eta, Csc PCA points), run, done / error / cancelled
    POST   /api/jobs/{id}/cancel       take it off the queue, or kill it

At most `settings.max_jobs` jobs run at once; the others are queued. A finished training job's
model joins the app's model registry (`/api/models` lists it, `PUT /api/models/selected` serves
it; after a restart the app finds it in its own models folder). The jobs are the app's
`JobManager` (server.jobs.manager), created in the lifespan.
"""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import StreamingResponse

from server.deps import JobsDep
from server.jobs.events import server_stopping, sse
from server.jobs.manager import JobManager
from server.jobs.presets import PRESETS
from server.schemas.jobs import Job, JobRequest

router = APIRouter(tags=["jobs"])
POLL_SECONDS = 0.5  # how often an open stream checks for a closed client or a stopping server
KEEP_ALIVE_SECONDS = 15.0


def _job(jobs: JobManager, job_id: str) -> dict:
    job = jobs.get(job_id)
    if job is None:
        raise HTTPException(404, f"no job {job_id!r}")
    return job


@router.get("/api/jobs", response_model=list[Job])
def list_jobs(jobs: JobsDep) -> list[dict]:
    return jobs.list()


@router.get("/api/jobs/presets")
def presets() -> dict:
    """{name: {title, scale, minutes: {mode: measured minutes}, labels: {mode: label}}}."""
    return {
        name: {
            "title": p.title,
            "scale": p.scale,
            "minutes": p.minutes,
            "labels": {mode: p.label(mode) for mode in p.minutes},
        }
        for name, p in PRESETS.items()
    }


@router.post("/api/jobs", response_model=Job, status_code=201)
def start_job(body: JobRequest, jobs: JobsDep) -> dict:
    """Queue a training job (one model, saved to the app's models folder) or an evaluation (K x N runs)."""
    params = body.model_dump(exclude={"kind"})
    drop = ("folds", "inits", "workers") if body.kind == "train" else ("fold", "name")
    for key in drop:
        params.pop(key)
    return jobs.start(body.kind, params)


@router.get("/api/jobs/{job_id}", response_model=Job)
def get_job(job_id: str, jobs: JobsDep) -> dict:
    return _job(jobs, job_id)


@router.post("/api/jobs/{job_id}/cancel", response_model=Job)
def cancel_job(job_id: str, jobs: JobsDep) -> dict:
    job = _job(jobs, job_id)
    if not jobs.cancel(job_id):
        raise HTTPException(409, f"job {job_id} is neither queued nor running (status {job['status']})")
    return _job(jobs, job_id)


@router.get("/api/jobs/{job_id}/events")
async def job_events(job_id: str, request: Request, jobs: JobsDep) -> StreamingResponse:
    """Server-Sent Events: a snapshot of the job, then every event until it ends (or the client
    leaves, or the server stops: an open stream never holds a shutdown)."""
    _job(jobs, job_id)
    loop = asyncio.get_running_loop()
    events: asyncio.Queue = asyncio.Queue()
    sub = jobs.subscribe(job_id, lambda e: loop.call_soon_threadsafe(events.put_nowait, e))

    def stopping() -> bool:
        return jobs.closing.is_set() or server_stopping()

    async def stream():
        try:
            yield sse({"type": "snapshot", "job": _job(jobs, job_id)})
            quiet = 0.0
            while jobs.is_active(job_id) or not events.empty():
                if stopping() or await request.is_disconnected():
                    return
                try:
                    event = await asyncio.wait_for(events.get(), timeout=POLL_SECONDS)
                except TimeoutError:
                    quiet += POLL_SECONDS
                    if quiet >= KEEP_ALIVE_SECONDS:
                        quiet = 0.0
                        yield ": keep-alive\n\n"
                    continue
                quiet = 0.0
                yield sse(event)
                if event["type"] in ("done", "error", "cancelled"):
                    return
        finally:
            jobs.unsubscribe(sub)

    return StreamingResponse(
        stream(),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
    )
