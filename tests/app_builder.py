"""The one way the tests and benchmarks build and serve the explorer app.

Every app is `server.app.create_app(settings, load_corpus, routers)`; what differs is what it
serves, and each of those has one function here:

    explorer(root)        the real corpus code and two untrained models (tests/server/explorer_artefacts)
    lesson_world(root)    the synthetic world of tests/server/lesson_world (64 scenes x 2 teachers)
    jobs_settings(root)   a jobs-only app (jobs and results routers) on the tiny scene set

and it runs in one of three ways: `TestClient(build_app(...))` in the test's process,
`serve_in_thread(app)` (uvicorn in a thread, for the browser tests), or `serve_in_process(args)`
(its own process, which a test may kill; `serve_jobs_app(root)` is the jobs-only app so).
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path

import httpx
import uvicorn
from fastapi import FastAPI

from server.app import CorpusLoader, create_app
from server.services.corpus import Corpus
from server.settings import Settings
from server.viewer import free_port

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "server"))

from explorer_artefacts import build_artefacts  # noqa: E402
from lesson_world import build, load_world  # noqa: E402

TINY_DATA = "tests.model.tiny_data:tiny_sequence_set"
JOBS_ROUTERS = ("jobs", "results")
TEST_CLIENT_HOST = "testserver"  # the Host header of fastapi.testclient.TestClient


def explorer(root: Path, **overrides: object) -> Settings:
    """Corpus + two untrained models under `root` (no 3D viewer unless `viser=True`)."""
    return dataclasses.replace(build_artefacts(root), **overrides)


def lesson_world(root: Path, **overrides: object) -> tuple[Settings, CorpusLoader]:
    """The synthetic world's settings (two untrained models under `root`) and its corpus loader."""
    return dataclasses.replace(build(root), **overrides), load_world


def jobs_settings(root: Path, **overrides: object) -> Settings:
    """A jobs-only app's settings: run store and models folder under `root`, the tiny scene set."""
    base = Settings(
        run_dir=root / "runs",
        models_dir=root / "models",
        user_dir=root / "user",
        job_data=TINY_DATA,
        viser=False,
    )
    return dataclasses.replace(base, **overrides)


def build_app(
    settings: Settings, load_corpus: CorpusLoader = Corpus.load, routers: Sequence[str] | None = None
) -> FastAPI:
    """The app of `settings` (all its routers, or the named ones); it also answers the Host name
    of Starlette's TestClient (``testserver``)."""
    settings = dataclasses.replace(settings, allowed_hosts=(*settings.allowed_hosts, TEST_CLIENT_HOST))
    return create_app(settings, load_corpus, routers)


def jobs_app() -> FastAPI:
    """`uvicorn --factory tests.app_builder:jobs_app`: the jobs-only app of the MTRNN_* settings."""
    return build_app(Settings.from_env(job_data=TINY_DATA, viser=False), routers=JOBS_ROUTERS)


def wait_until_up(url: str, timeout: float = 60.0, alive: Callable[[], bool] = lambda: True) -> None:
    """Poll `url` until it answers 200; raise when `timeout` passes or the server died."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            if httpx.get(url, timeout=2).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        if time.monotonic() > deadline or not alive():
            raise RuntimeError(f"{url} did not answer within {timeout:.0f} s")
        time.sleep(0.2)


@contextmanager
def serve_in_thread(app: FastAPI, timeout: float = 60.0) -> Iterator[str]:
    """uvicorn serving `app` in a thread of this process; yields its URL."""
    port = free_port()
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    url = f"http://127.0.0.1:{port}"
    try:
        wait_until_up(f"{url}/api/pages", timeout, thread.is_alive)
        yield url
    finally:
        server.should_exit = True
        thread.join(timeout=10)


@contextmanager
def serve_in_process(
    args: Sequence[str], env: dict[str, str] | None = None, timeout: float = 60.0, quiet: bool = False
) -> Iterator[tuple[str, subprocess.Popen]]:
    """`python -m <args> --port <free port>` in its own process; yields (URL, process)."""
    port = free_port()
    out = subprocess.DEVNULL if quiet else None
    proc = subprocess.Popen(
        [sys.executable, "-m", *args, "--port", str(port)], env=env, stdout=out, stderr=out, cwd=ROOT
    )
    url = f"http://127.0.0.1:{port}"
    try:
        wait_until_up(f"{url}/api/pages", timeout, lambda: proc.poll() is None)
        yield url, proc
    finally:
        if proc.poll() is None:
            proc.terminate()
        proc.wait(timeout=20)


def serve_jobs_app(
    root: Path, figures_dir: Path | None = None
) -> AbstractContextManager[tuple[str, subprocess.Popen]]:
    """The jobs-only app (run store and models under `root`) in its own process."""
    env = {
        **os.environ,
        "MTRNN_RUN_DIR": str(root / "runs"),
        "MTRNN_MODELS_DIR": str(root / "models"),
        "MTRNN_USER_DIR": str(root / "user"),
    }
    if figures_dir is not None:
        env["MTRNN_FIGURES_DIR"] = str(figures_dir)
    args = [
        "uvicorn",
        "--factory",
        "tests.app_builder:jobs_app",
        "--app-dir",
        str(ROOT),
        "--log-level",
        "warning",
    ]
    return serve_in_process(args, env)
