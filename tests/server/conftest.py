"""Fixtures of the API tests: one app on the real corpus code and real (untrained) models."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from explorer_artefacts import Exported
from fastapi.testclient import TestClient

from data.corpus import export_recording, load_corpus
from data.recording import write_npz, write_zip
from server.settings import Settings
from tests.app_builder import build_app, explorer


@pytest.fixture(scope="session")
def settings(tmp_path_factory: pytest.TempPathFactory) -> Settings:
    return explorer(tmp_path_factory.mktemp("explorer"))


@pytest.fixture(scope="session")
def client(settings: Settings) -> Iterator[TestClient]:
    with TestClient(build_app(settings)) as c:
        yield c


@pytest.fixture(scope="session")
def exported(settings: Settings, tmp_path_factory: pytest.TempPathFactory) -> Exported:
    """A corpus recording exported in format v1, as .zip and as .npz (what users upload)."""
    rid = load_corpus(settings.corpus_path).entries[0].id
    rec = export_recording(rid, 0)
    out = tmp_path_factory.mktemp("uploads")
    return Exported(rid, write_zip(rec, out / f"{rid}.zip"), write_npz(rec, out / f"{rid}.npz"))
