"""A live explorer (uvicorn + viser in a thread) and a headless Debian chromium driven by Playwright.

The app serves the shipped corpus and model when both exist (so the screenshots in docs/ show
the real thing; MTRNN_MODELS_DIR and MTRNN_CORPUS can point at others), else the test artefacts
of tests/server/. Chromium is never downloaded: the
tests use /usr/bin/chromium (`scripts/ensure-chromium` installs it) and skip without it.
"""

from __future__ import annotations

import dataclasses
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
import uvicorn

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "server"))
from explorer_artefacts import build_artefacts  # noqa: E402

from data.corpus import DEFAULT_PATH  # noqa: E402
from server.app import create_app  # noqa: E402
from server.settings import Settings  # noqa: E402
from server.viewer import free_port  # noqa: E402

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--enable-unsafe-swiftshader",  # WebGL without a GPU (the 3D view)
    "--use-angle=swiftshader",
    "--ignore-gpu-blocklist",
    "--disable-background-networking",
    "--disable-dev-shm-usage",
]


@pytest.fixture(scope="session")
def served(tmp_path_factory: pytest.TempPathFactory) -> Settings:
    shipped = Settings.from_env()  # MTRNN_MODELS_DIR / MTRNN_CORPUS may point elsewhere
    corpus = shipped.corpus_path or DEFAULT_PATH
    if corpus.is_file() and (shipped.models_dir / shipped.model / "meta.json").is_file():
        return dataclasses.replace(shipped, corpus_path=corpus)
    return build_artefacts(tmp_path_factory.mktemp("explorer-web"))


@pytest.fixture(scope="session")
def base_url(served: Settings) -> Iterator[str]:
    port = free_port()
    app = create_app(dataclasses.replace(served, viser=True, port=port))
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    url = f"http://127.0.0.1:{port}"
    deadline = time.time() + 60
    while time.time() < deadline:
        try:
            if httpx.get(f"{url}/api/health", timeout=2).status_code == 200:
                break
        except httpx.HTTPError:
            time.sleep(0.2)
    else:
        pytest.fail("the explorer did not start within 60 s")
    yield url
    server.should_exit = True
    thread.join(timeout=10)


@pytest.fixture(scope="session")
def browser() -> Iterator[object]:
    if not CHROMIUM.exists():
        pytest.skip("Debian chromium is not installed (run scripts/ensure-chromium)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture()
def page(browser, base_url: str) -> Iterator[object]:  # noqa: ANN001 - playwright Browser
    context = browser.new_context(viewport={"width": 1400, "height": 1000}, base_url=base_url)
    pg = context.new_page()
    pg.set_default_timeout(60_000)
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.errors = errors  # type: ignore[attr-defined]
    yield pg
    context.close()
