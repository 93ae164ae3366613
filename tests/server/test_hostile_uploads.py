"""The crafted uploads of issue 14 through the app: each answered 4xx with a message (or described,
with warnings where the recording carries words the model cannot say), never 5xx, the app still
answering after each; the body cap while receiving, the decode slots and the upload cache's bytes."""

from __future__ import annotations

import asyncio
import threading

import hostile_cases as hostile
import numpy as np
import pytest
from fastapi import HTTPException
from fastapi.testclient import TestClient

from data.recording import Recording
from server.routes.forms import _capped
from server.services.corpus import Corpus
from server.services.describe import DescribeService
from server.services.models import ModelRegistry
from server.settings import Settings

# what each crafted case is answered: a status, and a piece of its message
EXPECTED = {
    "csv_cell_over_field_limit": (400, "joints.csv line 3 is longer than 4096 bytes"),
    "time_stamps_1_7e308": (400, "the recording is too long"),
    "npz_fps_5e_324": (400, "fps must be from 0.01 to 10000"),
    "npz_fps_one_element_array": (200, ""),
    "npz_undecodable_utterance": (400, "utterance is bytes that are not UTF-8 text"),
    "deeply_nested_meta": (400, "meta.json is nested too deeply"),
    "exif_rotated_jpeg": (200, ""),
    "encrypted_member": (400, "is encrypted (password-protected)"),
    "npy_header_10e13_elements": (400, "declares shape (1085069444, 48, 64, 3)"),
    "frame_name_of_5000_digits": (200, ""),
    "png_640x999999": (413, "at most 4096 pixels a side"),
    "npz_1080p_fps_1_29": (400, "581 frames of 1920x1080 would take 3447 MB decoded"),
    "csv_3_5m_rows": (400, "joints.csv has more than 60000 rows"),
}


def service_of(settings: Settings, **options: int) -> DescribeService:
    """A describe service of its own (not the app's), over the test app's corpus and models."""
    corpus = Corpus.load(settings)
    return DescribeService(corpus, ModelRegistry.serving(settings, corpus), **options)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_a_crafted_upload_is_answered_with_its_problem(client: TestClient, name: str) -> None:
    case = hostile.CASES[name]()
    response = client.post(case.endpoint, files=case.files())
    status, message = EXPECTED[name]
    assert response.status_code == status, response.text
    if message:
        assert message in response.json()["detail"]
    assert client.get("/api/health").status_code == 200


def _unfamiliar(client: TestClient) -> list[str]:
    """The familiarity warnings of the cases' recording (a still arm, 1.5 s) without an utterance:
    they follow the utterance's warnings in every answer about it."""
    data = hostile.zip_of(hostile.recording_members())
    return client.post(hostile.DESCRIBE, files={"recording": ("plain.zip", data)}).json()["warnings"]


def test_an_utterance_with_an_unknown_word_is_described_with_a_warning(client: TestClient) -> None:
    case = hostile.unknown_word()
    body = client.post(case.endpoint, files=case.files()).json()
    assert body["expected"] == "slide the red xylophonezz." and body["correct"] is False
    assert body["target_activity"] is None
    assert body["warnings"] == [
        "the model's lexicon has no word 'xylophonezz': it can never say the expected utterance",
        "the expected utterance has no target activity: "
        "word 'xylophonezz' is not in the CMU pronouncing dictionary",
        *_unfamiliar(client),
    ]


def test_an_utterance_with_digits_is_described_with_a_warning(client: TestClient) -> None:
    case = hostile.digits_in_meta()
    body = client.post(case.endpoint, files=case.files()).json()
    assert isinstance(body["utterance"], str) and body["target_activity"] is None
    assert body["warnings"] == [
        "the model's lexicon has no word 'apples': it can never say the expected utterance",
        "the expected utterance has no target activity: "
        "unsupported character '2' in utterance 'push the 2 red apples.'",
        *_unfamiliar(client),
    ]


def test_a_corpus_upload_has_no_warnings(client: TestClient) -> None:
    case = hostile.Case(
        hostile.DESCRIBE, "ok.zip", hostile.zip_of(hostile.recording_members("push the red apple."))
    )
    body = client.post(case.endpoint, files=case.files()).json()
    assert body["warnings"] == _unfamiliar(client) and body["target_activity"] is not None
    assert all("learned from" in w for w in body["warnings"])  # only how unlike the corpus it is


@pytest.mark.parametrize(
    ("endpoint", "field", "cap"),
    [
        ("/api/describe", "recording", "server.routes.describe.MAX_UPLOAD_BYTES"),
        ("/api/lessons/seeing", "image", "server.routes.lessons.MAX_IMAGE_BYTES"),
    ],
)
def test_a_chunked_body_over_the_cap_is_413(
    client: TestClient, monkeypatch: pytest.MonkeyPatch, endpoint: str, field: str, cap: str
) -> None:
    monkeypatch.setattr(cap, 4096)
    boundary = b"b0undary"

    def body():  # noqa: ANN202 (no Content-Length: sent chunked)
        yield (
            b"--"
            + boundary
            + f'\r\nContent-Disposition: form-data; name="{field}"; filename="a.bin"\r\n\r\n'.encode()
        )
        for _ in range(200):
            yield bytes(1 << 14)

    headers = {"content-type": f"multipart/form-data; boundary={boundary.decode()}"}
    response = client.post(endpoint, content=body(), headers=headers)
    assert response.status_code == 413 and "larger than" in response.json()["detail"]
    assert client.get("/api/health").status_code == 200


def test_the_body_is_counted_while_it_arrives() -> None:
    """The capped receive refuses once the cap (plus the multipart framing) has arrived, and pulls
    nothing more from the connection."""
    pulled = []

    async def endless() -> dict:
        pulled.append(1)
        return {"type": "http.request", "body": bytes(1 << 14), "more_body": True}

    async def drain() -> None:
        receive = _capped(endless, 1 << 16, HTTPException(413, "too large"))
        while True:
            await receive()

    with pytest.raises(HTTPException) as info:
        asyncio.run(drain())
    assert info.value.status_code == 413
    assert len(pulled) == (2 << 16) // (1 << 14) + 1  # the first message over the cap


def test_uploads_beyond_the_decode_slots_get_503_with_retry_after(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("server.services.describe.SLOT_WAIT_S", 0.3)
    describe: DescribeService = client.app.state.services.describe
    case = hostile.Case(hostile.DESCRIBE, "ok.zip", hostile.zip_of(hostile.recording_members()))
    held = [describe.decode_slot(wait=0) for _ in range(describe.decode_slots)]
    for slot in held:
        slot.__enter__()
    try:
        response = client.post(case.endpoint, files=case.files())
    finally:
        for slot in held:
            slot.__exit__(None, None, None)
    assert response.status_code == 503 and int(response.headers["retry-after"]) > 0
    assert "send this one again" in response.json()["detail"]
    assert client.post(case.endpoint, files=case.files()).status_code == 200


def test_the_decode_slots_bound_concurrent_reads(settings: Settings) -> None:
    """Two slots, three uploads at once: one waits for a slot, none runs as a third."""
    service = service_of(settings, decode_slots=2)
    inside, peak, lock = 0, 0, threading.Lock()
    real = service.decode_slot

    def watched(wait: float = 10.0):  # noqa: ANN202
        ctx = real(wait)

        class Watch:
            def __enter__(self) -> None:
                nonlocal inside, peak
                ctx.__enter__()
                with lock:
                    inside += 1
                    peak = max(peak, inside)

            def __exit__(self, *exc: object) -> None:
                nonlocal inside
                with lock:
                    inside -= 1
                ctx.__exit__(*exc)

        return Watch()

    service.decode_slot = watched  # type: ignore[method-assign]
    data = hostile.zip_of(hostile.recording_members())
    threads = [threading.Thread(target=service.describe_upload, args=(data, f"{i}.zip")) for i in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert peak == 2


def test_the_upload_cache_is_bounded_in_bytes(settings: Settings) -> None:
    one = 30 * 48 * 64 * 3
    service = service_of(settings, cache_bytes=int(2.5 * one))
    ids = []
    for i in range(4):
        members = hostile.recording_members() | {"frames/000.png": hostile.png(hostile.frame() // (i + 2))}
        ids.append(service.describe_upload(hostile.zip_of(members), f"{i}.zip").id)
    kept = [uid for uid in ids if uid in service._uploads]
    assert kept == ids[-2:]  # two recordings of ~one frame budget each (plus encodings) fit
    assert sum(u.nbytes for u in service._uploads.values()) <= 2.5 * one


def test_the_newest_upload_is_kept_even_if_larger_than_the_cache(settings: Settings) -> None:
    service = service_of(settings, cache_bytes=1)
    up = service.describe_upload(hostile.zip_of(hostile.recording_members()), "a.zip")
    assert service.upload(up.id) is up and isinstance(up.recording, Recording)
    assert np.array_equal(service.frames(up.id), up.recording.frames)


def test_a_picture_for_the_seeing_lesson_must_come_in_its_field(client: TestClient) -> None:
    response = client.post("/api/lessons/seeing", files={"photo": ("a.png", b"\x89PNG", "image/png")})
    assert response.status_code == 422 and "field 'image'" in response.json()["detail"]
