"""`mtrnn describe RECORDING [--json]` gives the API's answer."""

from __future__ import annotations

import json

import pytest
from explorer_artefacts import Exported
from fastapi.testclient import TestClient

from server.cli import main
from server.settings import Settings


@pytest.fixture()
def env(settings: Settings, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MTRNN_MODELS_DIR", str(settings.models_dir))
    monkeypatch.setenv("MTRNN_CORPUS", str(settings.corpus_path))


def test_describe_json_equals_the_upload_answer(
    env: None, client: TestClient, exported: Exported, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["describe", str(exported.zip), "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    api = client.post(
        "/api/describe", files={"recording": (exported.zip.name, exported.zip.read_bytes())}
    ).json()
    for key in ("id", "utterance", "words", "phonemes", "expected", "correct", "activity", "csc"):
        assert cli[key] == api[key], key


def test_describe_prints_the_utterance_and_reports_bad_files(
    env: None, exported: Exported, tmp_path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["describe", str(exported.npz)]) == 0
    out = capsys.readouterr().out
    assert "expected:" in out and "phonemes:" in out
    bad = tmp_path / "bad.zip"
    bad.write_bytes(b"nope")
    assert main(["describe", str(bad)]) == 2
    assert "corrupt archive" in capsys.readouterr().out
