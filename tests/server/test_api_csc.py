"""GET /api/csc, /api/csc/neighbours and POST /api/csc/generate against the model and metrics."""

from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient

from data.corpus import load_corpus
from model import metrics
from model.checkpoint import load
from model.encoding.utterance import Lexicon
from server.settings import Settings


@pytest.fixture(scope="module")
def patterns(settings: Settings) -> dict[str, np.ndarray]:
    """Every corpus recording's Csc patterns, computed here directly from the model."""
    corpus = load_corpus(settings.corpus_path)
    model, meta = load(settings.models_dir / "default")
    ds = model.describe_batch(
        [e.proprioception for e in corpus.entries],
        [e.vision for e in corpus.entries],
        Lexicon(meta["lexicon"]),
    )
    return {
        "s": np.stack([d.csc_s for d in ds]).astype(np.float64),
        "v": np.stack([d.csc_v for d in ds]).astype(np.float64),
        "a": np.stack([d.csc_a for d in ds]).astype(np.float64),
        "actions": [e.scene.action for e in corpus.entries],
    }


@pytest.mark.parametrize("space", ["s", "v", "a"])
def test_csc_space_is_the_exact_pca_with_the_papers_measures(
    client: TestClient, patterns: dict, space: str
) -> None:
    body = client.get("/api/csc", params={"space": space}).json()
    x = patterns[space]
    coords = metrics.CscPCA(2).fit_transform(x)
    got = np.array([[p["x"], p["y"]] for p in body["points"]])
    assert np.allclose(got, coords, atol=1e-4)
    assert body["dims"] == x.shape[1] and len(body["points"]) == len(x)
    assert np.isclose(sum(body["explained_variance_ratio"]), 1.0, atol=1e-6)
    assert body["measures"]["d_avg"] == pytest.approx(metrics.d_avg(x), rel=1e-6)
    assert body["measures"]["d_rel"] == pytest.approx(metrics.d_rel(x), rel=1e-6)
    assert body["measures"]["d_inter"] == pytest.approx(metrics.d_inter(x, patterns["actions"]), rel=1e-6)
    assert body["measures"]["d_intra"] == pytest.approx(metrics.d_intra(x, patterns["actions"]), rel=1e-6)
    first = body["points"][0]
    assert {"id", "action", "colour", "shape", "split", "generated"} <= set(first)


def test_csc_space_must_be_s_v_or_a(client: TestClient) -> None:
    assert client.get("/api/csc", params={"space": "x"}).status_code == 422


def test_neighbours_are_nearest_in_the_original_space(client: TestClient, patterns: dict) -> None:
    ids = [p["id"] for p in client.get("/api/csc", params={"space": "v"}).json()["points"]]
    body = client.get("/api/csc/neighbours", params={"space": "v", "id": ids[0], "k": 3}).json()
    dist = np.linalg.norm(patterns["v"] - patterns["v"][0], axis=1)
    expected = [ids[i] for i in np.argsort(dist, kind="stable") if i != 0][:3]
    assert [n["id"] for n in body["neighbours"]] == expected
    assert [n["distance"] for n in body["neighbours"]] == sorted(n["distance"] for n in body["neighbours"])
    assert client.get("/api/csc/neighbours", params={"space": "v", "id": "nope-1"}).status_code == 404


def test_generate_from_a_plane_point_inverts_the_pca(
    client: TestClient, settings: Settings, patterns: dict
) -> None:
    pca = metrics.CscPCA(min(patterns["a"].shape)).fit(patterns["a"])
    body = client.post("/api/csc/generate", json={"point": [0.01, -0.02]}).json()
    z = np.zeros((1, pca.components_.shape[0]))
    z[0, :2] = (0.01, -0.02)
    c_a = pca.inverse_transform(z)[0]
    assert np.allclose(body["csc"], c_a, atol=1e-5)
    model, meta = load(settings.models_dir / "default")
    assert body["utterance"] == model.generate_from_csc(c_a, Lexicon(meta["lexicon"])).text
    assert body["point"] == [0.01, -0.02]


def test_generate_from_a_vector_projects_it_onto_the_plane(client: TestClient, patterns: dict) -> None:
    c_a = patterns["a"][0]
    body = client.post("/api/csc/generate", json={"csc": c_a.tolist()}).json()
    pca = metrics.CscPCA(2).fit(patterns["a"])
    assert np.allclose(body["point"], pca.transform(c_a[None])[0], atol=1e-5)
    assert body["nearest"]["distance"] == pytest.approx(0.0, abs=1e-5)


@pytest.mark.parametrize(
    "payload",
    [{}, {"point": [0, 0], "csc": [0.0] * 12}, {"csc": [0.0, 1.0]}, {"point": [1.0]}],
)
def test_generate_rejects_bad_requests_with_422(client: TestClient, payload: dict) -> None:
    response = client.post("/api/csc/generate", json=payload)
    assert response.status_code == 422 and response.json()["detail"]
