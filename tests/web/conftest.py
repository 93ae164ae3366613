"""A live explorer (uvicorn + viser in a thread) and a headless Debian chromium driven by Playwright.

The app serves the shipped corpus and model when both exist (so the screenshots in docs/ show
the real thing; MTRNN_MODELS_DIR and MTRNN_CORPUS can point at others), else the test artefacts
of tests/server/ (`tests.app_builder.explorer`). Chromium is never downloaded: the
tests use /usr/bin/chromium (`scripts/ensure-chromium` installs it) and skip without it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from data.corpus import DEFAULT_PATH
from server.settings import Settings
from tests.app_builder import build_app, explorer, serve_in_thread

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
    return explorer(tmp_path_factory.mktemp("explorer-web"))


@pytest.fixture(scope="session")
def base_url(served: Settings) -> Iterator[str]:
    with serve_in_thread(build_app(dataclasses.replace(served, viser=True))) as url:
        yield url


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
def open_page(browser) -> Iterator[Callable[..., object]]:  # noqa: ANN001 - playwright Browser
    """`open_page(base_url, timeout_ms=60_000)`: a fresh 1400x1000 page that records its JS errors
    in `page.errors`; closed after the test."""
    contexts = []

    def open_(base_url: str, timeout_ms: int = 60_000) -> object:
        context = browser.new_context(viewport={"width": 1400, "height": 1000}, base_url=base_url)
        contexts.append(context)
        pg = context.new_page()
        pg.set_default_timeout(timeout_ms)
        errors: list[str] = []
        pg.on("pageerror", lambda e: errors.append(str(e)))
        pg.errors = errors  # type: ignore[attr-defined]
        return pg

    yield open_
    for context in contexts:
        context.close()


@pytest.fixture()
def page(open_page: Callable[..., object], base_url: str) -> object:
    return open_page(base_url)
