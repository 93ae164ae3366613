"""Lesson 2, speaking in phonemes: a sentence as the auditory IO activity (eqs. 18-21), read back."""

from __future__ import annotations

import math

import numpy as np

from model.encoding.utterance import (
    PHONEMES,
    Lexicon,
    UtteranceParams,
    decode_activity,
    encode_utterance,
    spike_scale,
    text_to_phonemes,
)
from model.metrics import words_of
from server.lessons import DECODE_THRESHOLD, rounded
from server.services.errors import Invalid


def speak(text: str, gamma: int, omega: int, sigma2: float, nu: int, grammar: Lexicon | None) -> dict:
    """Encode a sentence as the auditory IO activity and read it back with the decoder."""
    text = text.strip()
    if not text:
        raise Invalid("type a sentence, e.g. 'slide the red apple.'")
    if len(text) > 160:
        raise Invalid(f"keep the sentence under 160 characters (got {len(text)})")
    if not (0 <= gamma <= 12 and 0 <= omega <= 12 and 1 <= nu <= 8):
        raise Invalid("gamma must be in 0..12, omega in 0..12 and nu in 1..8")
    if omega % 2:
        raise Invalid(f"omega must be even (spikes span -omega/2..omega/2), got {omega}")
    if not (math.isfinite(sigma2) and 0.05 <= sigma2 <= 4.0):
        raise Invalid(f"sigma^2 must be between 0.05 and 4, got {sigma2}")
    if gamma + nu < omega // 2:
        raise Invalid(
            "the first spike would start before t = 0: "
            f"need gamma + nu >= omega/2 ({gamma} + {nu} < {omega // 2})"
        )
    try:
        phonemes = text_to_phonemes(text)
    except ValueError as err:
        raise Invalid(str(err)) from None
    params = UtteranceParams(gamma=gamma, omega=omega, sigma2=sigma2, nu=nu)
    y = encode_utterance(phonemes, params).astype(np.float64)  # eqs. (18)-(21)
    # The softmax input z of eq. (19) is 0 for every neuron without a spike, so z = ln y - min ln y.
    lam = spike_scale(len(PHONEMES))  # eq. (20)
    logs = np.log(y)
    spikes = (logs - logs.min(axis=1, keepdims=True)) / lam  # g of eq. (18), max over overlaps
    decoded = decode_activity(y, DECODE_THRESHOLD)
    words = words_of(text)
    lexicon = Lexicon([*words, *(grammar.words if grammar else ())])
    read_back = lexicon.words_to_text(lexicon.phonemes_to_words(decoded))
    used = list(dict.fromkeys(PHONEMES.index(p) for p in phonemes))  # in order of first use (Fig. 8a)
    return {
        "text": text,
        "phonemes": phonemes,
        "params": {"gamma": gamma, "omega": omega, "sigma2": sigma2, "nu": nu},
        "lambda": round(lam, 4),
        "steps": len(y),
        "labels": [PHONEMES[i] for i in used],
        "spikes": rounded(spikes[:, used].T, 3),
        "activity": rounded(y[:, used].T, 3),
        "peak": round(float(y.max()), 4),
        "decoded": decoded,
        "read_back": read_back,
        "exact": decoded == phonemes,
    }
