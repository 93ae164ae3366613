"""GET /api/examples (the recordings to try) and GET /api/examples/{name} (one as a format-v1 .zip,
rendered on its first request and kept in the user folder); every example describes through
POST /api/describe."""

from __future__ import annotations

import io
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from data.examples import EXAMPLES
from data.recording import read_recording
from tests.app_builder import build_app, explorer


@pytest.fixture(scope="module")
def user_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("user")


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory, user_dir: Path) -> Iterator[TestClient]:
    settings = explorer(tmp_path_factory.mktemp("explorer"), user_dir=user_dir)
    with TestClient(build_app(settings)) as c:
        yield c


def test_the_list_names_each_example_with_its_download(client: TestClient) -> None:
    examples = client.get("/api/examples").json()["examples"]
    assert len(examples) >= 6 and [e["name"] for e in examples] == list(EXAMPLES)
    assert all(set(e) == {"name", "title", "description", "kind", "url"} for e in examples)
    assert {e["kind"] for e in examples} == {"corpus", "unlike"}
    assert all(e["url"] == f"/api/examples/{e['name']}" for e in examples)


def test_an_example_downloads_as_a_format_v1_zip_made_once(client: TestClient, user_dir: Path) -> None:
    first = client.get("/api/examples/low-resolution")
    assert first.status_code == 200 and first.headers["content-type"] == "application/zip"
    assert first.headers["content-disposition"] == 'attachment; filename="low-resolution.zip"'
    assert "joints.csv" in zipfile.ZipFile(io.BytesIO(first.content)).namelist()
    rec = read_recording(first.content, "low-resolution.zip")
    assert rec.frames.shape[1:3] == (120, 160) and rec.utterance == "push the yellow banana."
    kept = list((user_dir / "examples").iterdir())
    assert [p.suffix for p in kept] == [".zip"]  # written atomically: no temporary file left
    stamp = kept[0].stat().st_mtime_ns
    again = client.get("/api/examples/low-resolution")
    assert again.content == first.content and kept[0].stat().st_mtime_ns == stamp  # not made again


@pytest.mark.parametrize("name", ["nope", "corpus-fly-purple-cat-9", "low-resolution.zip", ".%2E"])
def test_an_unknown_example_is_404_with_a_message(client: TestClient, name: str) -> None:
    r = client.get(f"/api/examples/{name}")
    assert r.status_code == 404 and "/api/examples" in r.json()["detail"]


def test_a_path_outside_the_examples_is_not_served(client: TestClient) -> None:
    for path in ("/api/examples/..%2F..%2Fsettings.py", "/api/examples/%2Fetc%2Fpasswd"):
        assert client.get(path).status_code == 404


def _describe(client: TestClient, name: str) -> dict:
    data = client.get(f"/api/examples/{name}").content
    r = client.post("/api/describe", files={"recording": (f"{name}.zip", data)})
    assert r.status_code == 200, r.text
    return r.json()


def test_an_example_unlike_the_corpus_is_described(client: TestClient) -> None:
    body = _describe(client, "fast-teacher")
    assert body["source"] == "upload" and body["expected"] == "show me the red phone."
    assert isinstance(body["utterance"], str) and body["correct"] in (True, False)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(EXAMPLES))
def test_every_example_is_described_without_error(client: TestClient, name: str) -> None:
    body = _describe(client, name)
    assert body["expected"] == EXAMPLES[name].scene.utterance
    assert len(body["activity"]) > 0 and set(body["csc"]) == {"s", "v", "a"}
