"""The process a train or evaluate job runs in (spawned by `manager.JobManager`'s launcher thread).

It dies with the server: the kernel sends it SIGKILL when the thread that started it ends
(PR_SET_PDEATHSIG is tied to that *thread*, which is why one long-lived launcher thread starts
every job), and it exits at once if the server is already gone when it starts. It has its own
process group, so cancelling kills its worker pool too. It reports through `events` (a queue):
status, progress, then done or error; an error carries the message a person sees and, apart,
the traceback for the server's log.
"""

from __future__ import annotations

import ctypes
import logging
import os
import signal
import traceback
from typing import Any

from model.experiments.protocol import resolve
from server.jobs.events import public_error
from server.jobs.kinds import PROCESS_KINDS
from server.settings import Settings

logger = logging.getLogger(__name__)
PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int) -> None:
    """SIGKILL this process when the thread that started it ends; exit now if `parent` is gone."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    except OSError:
        logger.warning("prctl unavailable: a job may outlive a killed server")
    if os.getppid() != parent:  # the server died before prctl took effect
        os._exit(1)


def job_main(job: dict, events: Any, settings: Settings, parent: int) -> None:
    die_with_parent(parent)
    os.setpgrp()  # its own process group: cancelling kills the job's worker pool too
    import torch

    torch.set_num_threads(1)
    try:
        events.put({"type": "status", "status": "running"})
        load = resolve(settings.job_data)
        data = load(str(settings.corpus_path)) if settings.corpus_path else load()
        _, work = PROCESS_KINDS[job["kind"]]
        result = work(job["params"], events.put, data, settings)
        events.put({"type": "done", "result": result})
    except Exception as err:
        events.put({"type": "error", "error": public_error(err), "traceback": traceback.format_exc()})
