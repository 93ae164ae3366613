"""The lessons' REST endpoints (server/routes/lessons.py over server/lessons/), on the synthetic
world of `lesson_world` (64 scenes x 2 teachers, two untrained Table-1 models): every lesson answers
with numbers computed from the model and data, and every bad parameter gets a 4xx with a message."""

from __future__ import annotations

import dataclasses
import io
import json
import math
import time
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import pytest
from fastapi.testclient import TestClient

from data.scenario import Scene
from model.experiments.runstore import RunSpec, RunStore
from server.deps import get_settings
from server.lessons.abstracting import stored_sweeps
from tests.app_builder import build_app, lesson_world
from tests.server.lesson_world import render


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    # a short live cosine run keeps the tests fast
    settings, load_world = lesson_world(
        tmp_path_factory.mktemp("world"), cosine_epochs=40, cosine_snapshot_every=5
    )
    with TestClient(build_app(settings, load_world)) as c:
        yield c


def _detail(response) -> str:  # noqa: ANN001 - an httpx response
    detail = response.json()["detail"]
    return detail if isinstance(detail, str) else str(detail)


def test_index_lists_the_seven_lessons_the_models_and_one_recording_per_scene(client: TestClient) -> None:
    body = client.get("/api/lessons").json()
    assert [lesson["id"] for lesson in body["lessons"]] == [
        "timescales",
        "speaking",
        "seeing",
        "feeling",
        "abstracting",
        "associating",
        "generalising",
    ]
    assert body["model"] == "faithful" and set(body["models"]) == {"faithful", "end-to-end"}
    assert body["modes"] == {"faithful": "faithful", "end-to-end": "end_to_end"}
    assert len(body["scenes"]) == 64
    assert {s["split"] for s in body["scenes"]} == {"train", "test"}


# --- 1. timescales


def test_pulse_follows_eq3_and_slower_units_forget_more_slowly(client: TestClient) -> None:
    fast = client.get("/api/lessons/timescales/pulse", params={"tau": 2}).json()
    slow = client.get("/api/lessons/timescales/pulse", params={"tau": 70}).json()
    # eq. (3): first step of the pulse charges the unit by 1/tau
    assert fast["z"][10] == pytest.approx(0.5) and slow["z"][10] == pytest.approx(1 / 70, abs=1e-4)
    assert slow["half_life_steps"] == pytest.approx(math.log(0.5) / math.log(1 - 1 / 70), abs=0.01)
    assert slow["left_after_20_steps"] > fast["left_after_20_steps"]
    assert set(slow["references"]) == {"IO", "Cf", "Cs"}


@pytest.mark.parametrize("tau", ["0", "500", "nan", "abc"])
def test_pulse_rejects_a_timescale_out_of_range(client: TestClient, tau: str) -> None:
    r = client.get("/api/lessons/timescales/pulse", params={"tau": tau})
    assert r.status_code == 422 and _detail(r)


def test_activity_shows_every_layer_of_mtrnn_a_over_time(client: TestClient) -> None:
    body = client.get("/api/lessons/timescales/activity", params={"scene": "push-red-apple-0"}).json()
    layers = body["layers"]
    assert (len(layers["IO"]["y"]), len(layers["Cf"]["y"]), len(layers["Cs"]["y"])) == (43, 80, 23)
    assert all(len(row) == body["steps"] for layer in layers.values() for row in layer["y"])
    assert [layers[k]["tau"] for k in ("IO", "Cf", "Cs")] == [2, 5, 70]
    assert len(body["phoneme_at"]) == body["steps"] and body["expected"] == "push the red apple."


def test_activity_of_an_unknown_recording_is_404(client: TestClient) -> None:
    r = client.get("/api/lessons/timescales/activity", params={"scene": "juggle-red-apple-0"})
    assert r.status_code == 404 and "juggle-red-apple-0" in _detail(r)


# --- 2. speaking


def test_speaking_encodes_and_reads_back_a_sentence_with_the_paper_constants(client: TestClient) -> None:
    body = client.get("/api/lessons/speaking", params={"text": "slide the red apple."}).json()
    assert body["phonemes"][:5] == ["SIL", "S", "L", "AY", "D"]
    assert body["exact"] and body["read_back"] == "slide the red apple."
    assert body["peak"] == pytest.approx(0.9, abs=1e-3)  # eq. (20): a lone spike reaches 0.9
    assert body["labels"][:4] == ["SIL", "S", "L", "AY"]  # neurons in order of first use


def test_close_or_wide_spikes_merge_a_doubled_phoneme_for_the_decoder(client: TestClient) -> None:
    text = "the bookkeeper."  # B UH K K IY P ER: K twice in a row
    sharp = client.get("/api/lessons/speaking", params={"text": text}).json()
    assert sharp["exact"] and sharp["decoded"].count("K") == 2
    for params in ({"nu": 1}, {"sigma2": 2.0}):
        blurred = client.get("/api/lessons/speaking", params={"text": text, **params}).json()
        assert not blurred["exact"] and blurred["decoded"].count("K") == 1, params
    wide = client.get("/api/lessons/speaking", params={"text": text, "sigma2": 2.0}).json()
    assert wide["peak"] < sharp["peak"]


@pytest.mark.parametrize(
    ("params", "needle"),
    [
        ({"text": "push the florbix."}, "florbix"),
        ({"text": ""}, "sentence"),
        ({"text": "push", "omega": 3}, "even"),
        ({"text": "push", "sigma2": 0}, "sigma"),
        ({"text": "push", "gamma": 0, "nu": 1, "omega": 6}, "gamma + nu"),
        ({"text": "push", "nu": 0}, "nu"),
    ],
)
def test_speaking_rejects_bad_input_with_a_message(client: TestClient, params: dict, needle: str) -> None:
    r = client.get("/api/lessons/speaking", params=params)
    assert r.status_code == 422 and needle in _detail(r)


# --- 3. seeing


def test_seeing_shows_every_stage_of_the_pipeline_on_a_corpus_frame(client: TestClient) -> None:
    body = client.get("/api/lessons/seeing", params={"scene": "pull-blue-apple-0", "frame": 3}).json()
    assert [s["key"] for s in body["stages"]] == [
        "original",
        "mean_shift",
        "saturation",
        "edges",
        "object_mask",
        "contour",
        "rays",
    ]
    kinds = {s["key"]: s["image"].split(";", 1)[0] for s in body["stages"]}
    assert kinds["original"] == "data:image/jpeg"
    assert kinds["edges"] == kinds["object_mask"] == "data:image/png"
    assert body["found"] and len(body["features"]) == 21 and body["frames"] > 3
    assert body["features"][18] > body["features"][16]  # a blue object: B above R


def test_seeing_an_uploaded_picture(client: TestClient) -> None:
    frame = render(Scene("push", "red", "banana"))[0]
    ok, png = cv2.imencode(".png", cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    r = client.post("/api/lessons/seeing", files={"image": ("mine.png", png.tobytes(), "image/png")})
    assert r.status_code == 200
    body = r.json()
    assert body["source"] == "mine.png" and body["found"] and body["features"][16] > body["features"][18]


def test_the_colour_window_changes_the_mean_shift_stage(client: TestClient) -> None:
    small = client.get(
        "/api/lessons/seeing", params={"scene": "pull-blue-apple-0", "colour_radius": 4}
    ).json()
    large = client.get(
        "/api/lessons/seeing", params={"scene": "pull-blue-apple-0", "colour_radius": 64}
    ).json()
    assert small["stages"][1]["image"] != large["stages"][1]["image"]


@pytest.mark.parametrize(
    ("params", "status"),
    [
        ({"scene": "pull-blue-apple-0", "frame": 9999}, 422),
        ({"scene": "pull-blue-apple-0", "colour_radius": 100}, 422),
        ({"scene": "no-such-thing-0"}, 404),
    ],
)
def test_seeing_rejects_bad_parameters(client: TestClient, params: dict, status: int) -> None:
    r = client.get("/api/lessons/seeing", params=params)
    assert r.status_code == status and _detail(r)


def test_seeing_rejects_a_file_that_is_not_a_picture_and_an_oversized_one(client: TestClient) -> None:
    r = client.post("/api/lessons/seeing", files={"image": ("x.png", b"not a picture", "image/png")})
    assert r.status_code == 422 and "image" in _detail(r)
    big = io.BytesIO(b"\0" * (8 * 1024 * 1024 + 10))
    r = client.post("/api/lessons/seeing", files={"image": ("big.png", big, "image/png")})
    assert r.status_code == 413 and "MB" in _detail(r)
    assert client.get("/api/lessons").status_code == 200  # still answering


# --- 4. feeling


def test_feeling_overlays_one_action_on_the_four_shapes_and_compares_touch_and_sight(
    client: TestClient,
) -> None:
    body = client.get("/api/lessons/feeling", params={"action": "push", "colour": "red"}).json()
    assert [s["shape"] for s in body["series"]] == ["apple", "banana", "dice", "phone"]
    assert all(len(s["proprioception"]) == 5 for s in body["series"])
    rows = body["comparison"]["rows"]
    assert rows[0]["pair"] == "push red apple vs push blue phone"
    # in the synthetic world, as in the paper, the arm barely depends on the object
    assert rows[0]["joints_rms"] < rows[1]["joints_rms"]
    assert all(r["c_s"] >= 0 and r["c_v"] >= 0 for r in rows)


@pytest.mark.parametrize("params", [{"action": "juggle"}, {"colour": "purple"}])
def test_feeling_rejects_unknown_actions_and_colours(client: TestClient, params: dict) -> None:
    r = client.get("/api/lessons/feeling", params=params)
    assert r.status_code == 422 and "must be one of" in _detail(r)


# --- 5. abstracting


def use_run_dir(client: TestClient, run_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Point the app's run store (settings.run_dir) elsewhere for one test."""
    settings = dataclasses.replace(client.app.state.settings, run_dir=run_dir)
    monkeypatch.setitem(client.app.dependency_overrides, get_settings, lambda: settings)


def _wait(client: TestClient, run_id: str, timeout: float = 60.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        body = client.get(f"/api/lessons/abstracting/runs/{run_id}").json()
        if body["status"] in ("done", "failed"):
            return body
        time.sleep(0.05)
    raise AssertionError("the cosine run did not finish")


def test_a_live_cosine_run_streams_moving_csc_points_and_final_measures(client: TestClient) -> None:
    r = client.post("/api/lessons/abstracting/runs", json={"psi": 5e-5, "seed": 3})
    assert r.status_code == 202
    first = r.json()
    busy = client.post("/api/lessons/abstracting/runs", json={"psi": 1e-3, "seed": 3})
    body = _wait(client, first["id"])
    assert body["status"] == "done", body["error"]
    frames = body["frames"]
    assert len(frames) >= 2 and all(len(f["points"]) == 4 and len(f["points"][0]) == 2 for f in frames)
    assert frames[0]["points"] != frames[-1]["points"]  # the abstracted contexts moved
    assert 0 < body["result"]["d_rel"] <= 1 and body["result"]["d_avg"] > 0
    assert body["progress"] == 1.0
    # only one run at a time; asking for the same run again returns it; frames can be paged
    assert busy.status_code in (202, 409)
    if busy.status_code == 409:
        assert "in progress" in _detail(busy)
    again = client.post("/api/lessons/abstracting/runs", json={"psi": 5e-5, "seed": 3}).json()
    assert again["id"] == first["id"]
    tail = client.get(
        f"/api/lessons/abstracting/runs/{first['id']}", params={"since": len(frames) - 1}
    ).json()
    assert tail["frames"] == frames[-1:]


@pytest.mark.parametrize("body", [{"psi": -1}, {"psi": 0.5}, {"psi": 1e-4, "seed": -2}, {}])
def test_a_cosine_run_rejects_bad_parameters(client: TestClient, body: dict) -> None:
    r = client.post("/api/lessons/abstracting/runs", json=body)
    assert r.status_code == 422 and _detail(r)


def test_an_unknown_cosine_run_is_404(client: TestClient) -> None:
    r = client.get("/api/lessons/abstracting/runs/nope")
    assert r.status_code == 404 and "nope" in _detail(r)


def test_the_sweep_says_it_is_not_there_without_a_run_store_or_a_report(tmp_path: Path) -> None:
    body = stored_sweeps(tmp_path / "empty", tmp_path / "no-figures")
    assert body["available"] is False and "no run store" in body["reason"]
    assert body["psi_s"] == body["cosine"] == []
    assert not (tmp_path / "empty").exists()  # asking never creates a store


def test_a_fresh_clone_shows_the_sweeps_the_report_ships(
    client: TestClient, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    use_run_dir(client, tmp_path / "empty", monkeypatch)  # no run store: runs/ is not shipped
    body = client.get("/api/lessons/abstracting/sweep").json()
    shipped = json.loads((client.app.state.settings.figures_dir / "results.json").read_text())
    assert body["available"] is True and body["reason"] == ""
    assert [r["psi_s"] for r in body["psi_s"]] == [r["psi_s"] for r in shipped["psi_s"]]
    assert [r["mixed_f1"] for r in body["psi_s"]] == pytest.approx([r["mixed_f1"] for r in shipped["psi_s"]])
    assert [r["psi"] for r in body["cosine"]] == [r["psi"] for r in shipped["cosine"]]
    assert not (tmp_path / "empty").exists()  # asking never creates a store


def test_the_sweep_tabulates_a_stored_psi_s_sweep(
    client: TestClient, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    store = RunStore(tmp_path)
    for psi, f1s in ((1e-4, (0.5, 0.7)), (5e-4, (0.8, 0.9))):
        for init, f1 in enumerate(f1s):
            spec = RunSpec("psi_s", "faithful", 0, init, init, {}, {"psi_s": psi})
            store.register([spec])
            store.finish(spec.key, {"mixed": {"f1": f1}}, 1.0)
    use_run_dir(client, tmp_path, monkeypatch)
    body = client.get("/api/lessons/abstracting/sweep").json()
    assert body["available"] is True
    assert [row["psi_s"] for row in body["psi_s"]] == [1e-4, 5e-4]
    assert [row["mixed_f1"] for row in body["psi_s"]] == pytest.approx([0.6, 0.85])
    assert body["psi_s"][0]["d_avg"] is None  # not stored: no number invented


# --- 6. associating


def test_associating_shows_three_spaces_and_muting_moves_the_auditory_context(client: TestClient) -> None:
    plain = client.get("/api/lessons/associating", params={"scene": "push-red-apple-0"}).json()
    assert set(plain["spaces"]) == {"s", "v", "a"}
    n = len(plain["labels"])
    assert all(len(plain["spaces"][s]["x"]) == n for s in "sva")
    i = plain["index"]
    assert plain["labels"][i]["id"] == "push-red-apple-0"
    a = plain["spaces"]["a"]
    assert plain["point_a"] == pytest.approx([a["x"][i], a["y"][i]], abs=1e-6)  # unmuted: its own point
    assert plain["moved"] == 0.0
    for mute in ("vision", "proprioception"):
        muted = client.get(
            "/api/lessons/associating", params={"scene": "push-red-apple-0", "mute": mute}
        ).json()
        assert muted["moved"] > 0 and not np.allclose(muted["point_a"], plain["point_a"], atol=1e-9), mute
        assert set(muted["slots"]) == {"action", "colour", "object"}


@pytest.mark.parametrize(
    ("params", "status"),
    [({"scene": "push-red-apple-0", "mute": "smell"}, 422), ({"scene": "nope-0"}, 404), ({}, 422)],
)
def test_associating_rejects_bad_parameters(client: TestClient, params: dict, status: int) -> None:
    r = client.get("/api/lessons/associating", params=params)
    assert r.status_code == status and _detail(r)


# --- 7. generalising


def test_generalising_scores_every_scene_of_each_model_against_its_split(client: TestClient) -> None:
    for name in ("faithful", "end-to-end"):
        body = client.get("/api/lessons/generalising", params={"model": name}).json()
        assert body["model"] == name and len(body["scenes"]) == 64
        assert body["train"]["recordings"] == 64 and body["test"]["recordings"] == 64
        novel = [s for s in body["scenes"] if s["split"] == "test"]
        # each object is trained with two actions, so every novel scene's object was seen
        assert all(s["seen"]["object"] for s in novel)
        assert body["test_object_seen"]["recordings"] == 64 and body["test_object_unseen"]["recordings"] == 0
        for s in body["scenes"]:
            assert 0.0 <= s["exact"] <= 1.0 and len(s["recordings"]) == 2


def test_generalising_an_unknown_model_is_404(client: TestClient) -> None:
    r = client.get("/api/lessons/generalising", params={"model": "nope"})
    assert r.status_code == 404 and "faithful" in _detail(r)


def test_feeling_gives_each_hand_path_in_cm_and_what_the_served_model_reads(client: TestClient) -> None:
    body = client.get("/api/lessons/feeling", params={"action": "slide", "colour": "red"}).json()
    assert body["reads"] in ("joints", "joints+hand", "hand")
    assert body["object_motion"] in ("none", "visual", "somatosensory")
    for s in body["series"]:
        path = np.asarray(s["hand_path"])
        assert path.shape == (3, len(s["proprioception"][0]))
        assert np.all(path[:, 0] == 0)  # relative to where the hand started
        assert np.abs(path).max() < 45 and np.abs(path).max() > 0.5  # cm: the NAO arm reaches ~22 cm
    rows = body["comparison"]["rows"]
    assert all(r["hand_rms"] >= 0 for r in rows)
    # as for the joints, in the synthetic world the hand barely depends on the object
    assert rows[0]["hand_rms"] < rows[1]["hand_rms"]
