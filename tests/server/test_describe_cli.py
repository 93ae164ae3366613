"""`mtrnn describe RECORDING [--json]` gives the API's answer on stdout, loads the model and its
lexicon but not the corpus, and reports bad files on stderr."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

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
    cli = json.loads(capsys.readouterr().out)  # stdout holds the answer and nothing else
    api = client.post(
        "/api/describe", files={"recording": (exported.zip.name, exported.zip.read_bytes())}
    ).json()
    for key in ("id", "utterance", "words", "phonemes", "expected", "correct", "activity", "csc"):
        assert cli[key] == api[key], key


def test_describe_prints_the_utterance_and_reports_bad_files(
    env: None, exported: Exported, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["describe", str(exported.npz)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 4 and out[1].startswith("expected:") and out[2].startswith("phonemes:")
    bad = tmp_path / "bad.zip"
    bad.write_bytes(b"nope")
    assert main(["describe", str(bad)]) == 2
    printed = capsys.readouterr()
    assert printed.out == "" and "corrupt archive" in printed.err


def test_describe_needs_no_corpus_when_the_model_has_its_lexicon(
    env: None,
    exported: Exported,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["describe", str(exported.zip)]) == 0
    with_corpus = capsys.readouterr().out
    monkeypatch.setenv("MTRNN_CORPUS", str(tmp_path / "no-corpus.npz"))
    assert main(["describe", str(exported.zip)]) == 0
    assert capsys.readouterr().out.splitlines()[:3] == with_corpus.splitlines()[:3]


def test_a_model_without_a_lexicon_speaks_the_corpus_words(
    env: None,
    settings: Settings,
    exported: Exported,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["describe", str(exported.zip), "--json"]) == 0
    with_lexicon = json.loads(capsys.readouterr().out)
    models = tmp_path / "models"
    shutil.copytree(settings.models_dir / "default", models / "default")
    meta = json.loads((models / "default" / "meta.json").read_text())
    del meta["lexicon"]
    (models / "default" / "meta.json").write_text(json.dumps(meta))
    monkeypatch.setenv("MTRNN_MODELS_DIR", str(models))
    assert main(["describe", str(exported.zip), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["utterance"] == with_lexicon["utterance"]


def test_describe_without_a_model_says_so(
    env: None,
    exported: Exported,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setenv("MTRNN_MODELS_DIR", str(tmp_path / "none"))
    assert main(["describe", str(exported.zip)]) == 2
    printed = capsys.readouterr()
    assert printed.out == "" and "no model under" in printed.err
