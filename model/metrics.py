"""Evaluation measures of the paper (3.2.2 and 4.3): utterance quality and Csc structure.

Utterances (4.3) are scored on the phoneme level, as the paper does, and on the word level:

- `edit_distance`: weighted Levenshtein distance with insertion 1, deletion 1, substitution 2
  (`model.encoding.words.align`, shared with the lexicon's nearest word), normalised by the
  target length; the matched pairs of the minimum-edit alignment are a longest common subsequence.
- `phoneme_f1`: precision = matched / |produced|, recall = matched / |target| over that alignment.
- `sentence_exact`, `word_accuracy`, `slot_accuracy` (action, colour, object of "ACT the COL OBJ.").
- `mixed(train, test)`: the paper's "mixed" measure, train and test weighted equally.

Csc measures (eqs. 13-15, 22-23) on abstracted context vectors (one row per sequence):

- `pairwise_distances` (eq. 13), `d_avg` (eq. 14), `d_rel` (eq. 15).
- `d_inter` (eq. 22) and `d_intra` (eq. 23). The paper's names are kept although they are swapped
  with respect to common usage: **d_inter is the mean distance within a cluster** (averaged over
  clusters) and **d_intra is the mean distance between cluster centroids**.
- `CscPCA`: exact-SVD PCA of Csc patterns with a deterministic sign convention.

Over runs: `mean_sem`, the mean and standard error of a measure (finite values only).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from model.encoding.words import align, raw_edit_distance, words_of


def edit_distance(produced: Sequence[str], target: Sequence[str], **costs: float) -> float:
    """Weighted edit distance normalised by the target length (paper 4.3; `costs` as `align`'s).

    An empty target divides by 1 (the distance is then the number of produced symbols times `ins`).
    """
    return raw_edit_distance(produced, target, **costs) / max(len(target), 1)


def phoneme_f1(produced: Sequence[str], target: Sequence[str]) -> tuple[float, float, float]:
    """(precision, recall, F1) from the minimum-edit alignment.

    precision = matched / |produced|, recall = matched / |target|; an empty side gives 0 for its
    ratio, and two empty sequences score (1, 1, 1).
    """
    if not produced and not target:
        return 1.0, 1.0, 1.0
    matched = align(produced, target).matches
    precision = matched / len(produced) if produced else 0.0
    recall = matched / len(target) if target else 0.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return precision, recall, f1


def _normalise(text: str) -> str:
    return " ".join(text.lower().split())


def sentence_exact(produced_text: str, target_text: str) -> bool:
    """True if the sentences are equal up to case and whitespace (punctuation counts)."""
    return _normalise(produced_text) == _normalise(target_text)


def word_accuracy(produced_text: str, target_text: str) -> float:
    """Matched words of the minimum-edit word alignment / max(|produced|, |target|), in [0, 1].

    Punctuation is ignored; 1 only when the word sequences are identical.
    """
    produced, target = words_of(produced_text), words_of(target_text)
    if not produced and not target:
        return 1.0
    return align(produced, target).matches / max(len(produced), len(target))


SLOTS = ("action", "colour", "object")


def parse_slots(
    text: str,
    actions: Sequence[str] | None = None,
    colours: Sequence[str] | None = None,
    objects: Sequence[str] | None = None,
) -> dict[str, str | None]:
    """The (action, colour, object) of "ACT the COL OBJ."; None for a slot that cannot be read.

    Without vocabularies the sentence is read by position around the first "the": the words
    before it are the action, and exactly two words must follow (colour, object). With all three
    vocabularies each slot is found on its own: the action is the longest vocabulary phrase the
    sentence starts with, colour and object are the single distinct vocabulary word of that kind
    present (none or several different ones -> None), so one garbled word costs only its own slot.
    """
    words = words_of(text)
    if actions is not None and colours is not None and objects is not None:
        action = None
        for phrase in sorted(actions, key=lambda a: -len(a.split())):
            if words[: len(phrase.split())] == phrase.split():
                action = phrase
                break
        found_colours = list(dict.fromkeys(w for w in words if w in colours))
        found_objects = list(dict.fromkeys(w for w in words if w in objects))
        return {
            "action": action,
            "colour": found_colours[0] if len(found_colours) == 1 else None,
            "object": found_objects[0] if len(found_objects) == 1 else None,
        }
    if "the" not in words:
        return dict.fromkeys(SLOTS)
    k = words.index("the")
    after = words[k + 1 :]
    return {
        "action": " ".join(words[:k]) or None,
        "colour": after[0] if len(after) == 2 else None,
        "object": after[1] if len(after) == 2 else None,
    }


def slot_accuracy(
    produced_text: str, target_text: str, *vocabularies: Sequence[str] | None
) -> dict[str, float]:
    """1.0 or 0.0 per slot (action, colour, object); an unreadable produced slot scores 0.
    `vocabularies` (actions, colours, objects) as `parse_slots` takes them.

    Raises ValueError if the target itself is not a sentence "ACT the COL OBJ.".
    """
    target = parse_slots(target_text, *vocabularies)
    if any(v is None for v in target.values()):
        raise ValueError(f"target {target_text!r} is not a sentence 'ACT the COL OBJ.'")
    produced = parse_slots(produced_text, *vocabularies)
    return {s: float(produced[s] == target[s]) for s in SLOTS}


def mean_sem(values: Iterable[float | None]) -> tuple[float, float, int]:
    """Mean, standard error (std with ddof 1 over sqrt(n); 0 for one value) and n of the finite
    values; (nan, nan, 0) when there are none."""
    a = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=np.float64)
    if a.size == 0:
        return math.nan, math.nan, 0
    sem = float(a.std(ddof=1) / math.sqrt(a.size)) if a.size > 1 else 0.0
    return float(a.mean()), sem, int(a.size)


def paired_difference(
    after: Sequence[float | None], before: Sequence[float | None]
) -> tuple[float, float, int, float]:
    """Mean and standard error of after - before over the pairs where both are finite (runs with
    the same seed: a paired design), their number, and the two-sided p of the paired t-test (nan
    below two pairs or when every difference is the same)."""
    from scipy.stats import ttest_rel

    pairs = [
        (a, b)
        for a, b in zip(after, before, strict=True)
        if a is not None and b is not None and math.isfinite(a) and math.isfinite(b)
    ]
    mean, sem, n = mean_sem([a - b for a, b in pairs])
    if n < 2 or sem == 0:
        return mean, sem, n, math.nan
    return mean, sem, n, float(ttest_rel([a for a, _ in pairs], [b for _, b in pairs]).pvalue)


def mixed(train: float, test: float) -> float:
    """The paper's "mixed" measure (4.3, Fig. 9): training and test results with equal weight."""
    return (train + test) / 2.0


@dataclass(frozen=True)
class Transcript:
    """One utterance as phonemes (what the network produced or should produce) and as text."""

    phonemes: tuple[str, ...]
    text: str


@dataclass(frozen=True)
class SequenceScores:
    """All utterance measures of one produced sequence against its target."""

    edit_distance: float
    precision: float
    recall: float
    f1: float
    sentence_exact: float
    word_accuracy: float
    slot_action: float
    slot_colour: float
    slot_object: float


def score(produced: Transcript, target: Transcript, *vocabularies: Sequence[str] | None) -> SequenceScores:
    """Score one production (phoneme measures on phonemes, word measures on text; `vocabularies`
    as `parse_slots` takes them)."""
    precision, recall, f1 = phoneme_f1(produced.phonemes, target.phonemes)
    slots = slot_accuracy(produced.text, target.text, *vocabularies)
    return SequenceScores(
        edit_distance=edit_distance(produced.phonemes, target.phonemes),
        precision=precision,
        recall=recall,
        f1=f1,
        sentence_exact=float(sentence_exact(produced.text, target.text)),
        word_accuracy=word_accuracy(produced.text, target.text),
        slot_action=slots["action"],
        slot_colour=slots["colour"],
        slot_object=slots["object"],
    )


def summarise(
    pairs: Iterable[tuple[Transcript, Transcript]], *vocabularies: Sequence[str] | None
) -> dict[str, float]:
    """Means of every `SequenceScores` field over (produced, target) pairs of one split, plus `n`."""
    scores = [asdict(score(p, t, *vocabularies)) for p, t in pairs]
    if not scores:
        raise ValueError("summarise needs at least one (produced, target) pair")
    summary = {k: float(np.mean([s[k] for s in scores])) for k in scores[0]}
    summary["n"] = float(len(scores))
    return summary


# --- Csc measures -------------------------------------------------------------------------------


def _as_points(points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
    x = np.asarray(points, dtype=np.float64)
    if x.ndim != 2:
        raise ValueError(f"expected a 2-D array of patterns (sequences x units), got shape {x.shape}")
    if x.shape[0] < 2:
        raise ValueError(f"distance measures need at least 2 patterns, got {x.shape[0]}")
    return x


def pairwise_distances(points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
    """Euclidean distances d(c_k, c_l) for all k < l (eq. 13), in row-major pair order."""
    x = _as_points(points)
    k, l = np.triu_indices(x.shape[0], k=1)
    return np.sqrt(((x[k] - x[l]) ** 2).sum(axis=1))


def d_avg(points: np.ndarray | Sequence[Sequence[float]]) -> float:
    """Mean distance over all |S|(|S|-1)/2 pairs of patterns (eq. 14)."""
    return float(pairwise_distances(points).mean())


def d_rel(points: np.ndarray | Sequence[Sequence[float]]) -> float:
    """Geometric mean of d(c_k, c_l) / d_avg over all pairs (eq. 15), computed in log space.

    1.0 iff all distances are equal; two identical patterns make a factor zero, so the product
    (and the result) is 0.0, as is the case of all patterns coinciding (d_avg = 0).
    """
    d = pairwise_distances(points)
    mean = d.mean()
    if mean == 0.0 or np.any(d == 0.0):
        return 0.0
    return float(np.exp(np.mean(np.log(d / mean))))


def _clusters(points: np.ndarray | Sequence[Sequence[float]], labels: Sequence) -> list[np.ndarray]:
    x = np.asarray(points, dtype=np.float64)
    lab = np.asarray(labels)
    if x.ndim != 2 or lab.shape != (x.shape[0],):
        raise ValueError(f"need one label per pattern: {x.shape} patterns, {lab.shape} labels")
    return [x[lab == u] for u in np.unique(lab)]


def d_inter(points: np.ndarray | Sequence[Sequence[float]], labels: Sequence) -> float:
    """Eq. (22), the paper's "inter-cluster distance": the mean over clusters of d_avg *within*
    each cluster (e.g. all patterns of one manipulation). Every cluster needs >= 2 patterns."""
    clusters = _clusters(points, labels)
    for c in clusters:
        if len(c) < 2:
            raise ValueError("d_inter needs at least 2 patterns in every cluster")
    return float(np.mean([d_avg(c) for c in clusters]))


def d_intra(points: np.ndarray | Sequence[Sequence[float]], labels: Sequence) -> float:
    """Eq. (23), the paper's "intra-cluster distance": the mean distance *between* the centroids
    of the clusters. Needs >= 2 clusters."""
    clusters = _clusters(points, labels)
    if len(clusters) < 2:
        raise ValueError("d_intra needs at least 2 clusters")
    return d_avg(np.stack([c.mean(axis=0) for c in clusters]))


class CscPCA:
    """PCA of Csc patterns (scikit-learn, exact SVD) with a deterministic sign convention.

    Each component is flipped so that its largest-magnitude loading is positive, so the picture
    does not mirror between runs or library versions. `inverse_transform` maps a point of the
    plane back to Csc space (e.g. to let the generator speak from any point of the auditory plane).

    >>> pca = CscPCA(2).fit(np.eye(4))
    >>> pca.transform(np.eye(4)).shape
    (4, 2)
    """

    def __init__(self, n_components: int = 2) -> None:
        if n_components < 1:
            raise ValueError(f"n_components must be >= 1, got {n_components}")
        self.n_components = n_components

    def fit(self, points: np.ndarray | Sequence[Sequence[float]]) -> CscPCA:
        x = _as_points(points)
        if self.n_components > min(x.shape):
            raise ValueError(
                f"n_components={self.n_components} exceeds min(patterns, units) = {min(x.shape)}"
            )
        from sklearn.decomposition import PCA  # here, not at import: the CLI's describe never fits one

        pca = PCA(n_components=self.n_components, svd_solver="full").fit(x)
        components = pca.components_.copy()
        largest = np.argmax(np.abs(components), axis=1)
        signs = np.sign(components[np.arange(len(components)), largest])
        self.components_ = components * signs[:, None]
        self.mean_ = pca.mean_.copy()
        self.explained_variance_ = pca.explained_variance_.copy()
        self.explained_variance_ratio_ = pca.explained_variance_ratio_.copy()
        return self

    def _check_fitted(self) -> None:
        if not hasattr(self, "components_"):
            raise RuntimeError("CscPCA is not fitted; call fit() first")

    def transform(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        self._check_fitted()
        x = np.asarray(points, dtype=np.float64)
        return (x - self.mean_) @ self.components_.T

    def fit_transform(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        return self.fit(points).transform(points)

    def inverse_transform(self, projected: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        self._check_fitted()
        z = np.asarray(projected, dtype=np.float64)
        return z @ self.components_ + self.mean_
