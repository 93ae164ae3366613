"""The one Csc survey: every corpus recording described once per model, and the PCA of its spaces.

`Survey` holds, per recording, the generated text and the three Csc vectors the paper studies
(c_s,T of MTRNN_s, c_v,T of MTRNN_v, c_a,0 from the cell assemblies; Fig. 10). `SurveyService`
computes it once per model (in batches, so that describe requests interleave) and derives, also
once, the Csc spaces of the API (full PCA and the cluster measures, eqs. 14-15, 22-23) and the
2-component PCA the lessons draw.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from model.metrics import CscPCA, d_avg, d_inter, d_intra, d_rel
from model.multimtrnn import csc_vectors
from server.services.corpus import Corpus
from server.services.errors import Unavailable
from server.services.models import LoadedModel, ModelRegistry

logger = logging.getLogger(__name__)

SPACES = ("s", "v", "a")
BATCH = 32  # recordings described under the model lock at a time


@dataclass
class CscSpaceData:
    """The Csc patterns of every corpus recording in one space, and their PCA."""

    vectors: np.ndarray  # [N, units]
    coords: np.ndarray  # [N, 2]
    pca: CscPCA
    explained_variance: list[float]
    explained_variance_ratio: list[float]
    measures: dict[str, float]


@dataclass
class Survey:
    """Every corpus recording described once by one model: texts and the three Csc vectors."""

    model: str
    ids: list[str]
    texts: list[str]
    c_s: np.ndarray  # [N, |Csc_s|] c_s,T
    c_v: np.ndarray  # [N, |Csc_v|] c_v,T
    c_a: np.ndarray  # [N, |Csc_a|] c_a,0
    spaces: dict[str, CscSpaceData] = field(default_factory=dict)  # filled by SurveyService.spaces

    def __post_init__(self) -> None:
        self._index = {rid: i for i, rid in enumerate(self.ids)}

    def vectors(self, space: str) -> np.ndarray:
        return {"s": self.c_s, "v": self.c_v, "a": self.c_a}[space]

    def said(self, rid: str) -> str | None:
        """What the model said about recording `rid` (None for one outside the survey)."""
        i = self._index.get(rid)
        return None if i is None else self.texts[i]


def _space(x: np.ndarray, actions: list[str]) -> CscSpaceData:
    full = CscPCA(min(x.shape)).fit(x)
    measures = {
        "d_avg": d_avg(x),
        "d_rel": d_rel(x),
        "d_inter": d_inter(x, actions),
        "d_intra": d_intra(x, actions),
    }
    return CscSpaceData(
        vectors=x,
        coords=full.transform(x)[:, :2],
        pca=full,
        explained_variance=[float(v) for v in full.explained_variance_],
        explained_variance_ratio=[float(v) for v in full.explained_variance_ratio_],
        measures={k: float(v) for k, v in measures.items()},
    )


class SurveyService:
    """Surveys of the corpus, one per model, computed on first use and kept."""

    def __init__(self, corpus: Corpus, models: ModelRegistry) -> None:
        self.corpus, self.models = corpus, models
        self._surveys: dict[str, Survey] = {}
        self._pcas: dict[tuple[str, str], tuple[CscPCA, np.ndarray]] = {}
        self._lock = threading.Lock()  # one survey computation at a time
        self._started: set[str] = set()  # models whose survey `ready` has set going
        self._starting = threading.Lock()

    def survey(self, name: str | None = None) -> Survey:
        """The survey of the named model (default: the served one)."""
        lm = self.models.get(name)
        with self._lock:
            if lm.name not in self._surveys:
                self._surveys[lm.name] = self._describe_all(lm)
            return self._surveys[lm.name]

    def ready(self, name: str | None = None) -> Survey | None:
        """The named model's survey (default: the served one's) if it is computed; else None, and
        it is set going in the background once, so that a list of recordings never waits for it."""
        lm = self.models.get(name)
        survey = self._surveys.get(lm.name)
        if survey is None:
            with self._starting:
                if lm.name not in self._started:
                    self._started.add(lm.name)
                    threading.Thread(
                        target=self._survey_quietly, args=(lm.name,), name="survey", daemon=True
                    ).start()
        return survey

    def _survey_quietly(self, name: str) -> None:
        try:
            self.survey(name)
        except Exception:  # whoever asks `survey` later gets the error with its message
            logger.exception("could not survey the corpus with model %r", name)

    def _describe_all(self, lm: LoadedModel) -> Survey:
        entries = list(self.corpus.entries.values())
        if len(entries) < 2:
            raise Unavailable("the corpus needs at least two recordings")
        started = time.perf_counter()
        described = []
        for start in range(0, len(entries), BATCH):
            batch = entries[start : start + BATCH]
            with self.models.lock:
                described += lm.model.describe_batch(
                    [e.proprioception for e in batch], [e.vision for e in batch], lm.lexicon
                )
        vectors = csc_vectors(described)
        survey = Survey(
            model=lm.name,
            ids=[e.id for e in entries],
            texts=[d.text for d in described],
            c_s=vectors["somatosensory"].astype(np.float64),
            c_v=vectors["visual"].astype(np.float64),
            c_a=vectors["auditory"].astype(np.float64),
        )
        logger.info(
            "survey: %s described %d recordings in %.1f s",
            lm.name,
            len(entries),
            time.perf_counter() - started,
        )
        return survey

    def spaces(self, name: str | None = None) -> Survey:
        """The survey with its Csc spaces (full PCA and cluster measures) computed."""
        survey = self.survey(name)
        with self._lock:
            if not survey.spaces:
                actions = [self.corpus.entries[rid].scene.action for rid in survey.ids]
                survey.spaces.update({s: _space(survey.vectors(s), actions) for s in SPACES})
            return survey

    def pca2(self, name: str, space: str) -> tuple[CscPCA, np.ndarray]:
        """PCA (2 components) of one Csc space of a model's survey, and the projected points."""
        survey = self.survey(name)
        with self._lock:
            key = (survey.model, space)
            if key not in self._pcas:
                pca = CscPCA(2).fit(survey.vectors(space))
                self._pcas[key] = (pca, pca.transform(survey.vectors(space)))
            return self._pcas[key]

    def warm_up(self) -> None:
        """Survey the served model before anyone asks (the Csc pages and lessons 4, 6, 7 need it)."""
        try:
            self.spaces()
        except Exception:  # whoever asks later gets the error with its message
            logger.exception("could not survey the corpus with the served model")

    def inverse_point(self, x: float, y: float) -> np.ndarray:
        """The c_a,0 at a point of the auditory PCA plane (other components at the mean)."""
        data = self.spaces().spaces["a"]
        z = np.zeros((1, len(data.explained_variance)))
        z[0, :2] = (x, y)
        return data.pca.inverse_transform(z)[0]

    def project_a(self, c_a: np.ndarray) -> tuple[float, float]:
        p = self.spaces().spaces["a"].pca.transform(c_a[None, :])[0]
        return float(p[0]), float(p[1])

    def nearest(
        self, space: str, vector: np.ndarray, k: int, exclude: str | None = None
    ) -> list[tuple[str, float]]:
        """The k recordings whose Csc pattern is closest to `vector` (Euclidean, original space)."""
        survey = self.spaces()
        dist = np.linalg.norm(survey.spaces[space].vectors - vector[None, :], axis=1)
        order = [i for i in np.argsort(dist, kind="stable") if survey.ids[i] != exclude]
        return [(survey.ids[i], float(dist[i])) for i in order[:k]]
