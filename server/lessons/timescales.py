"""Lesson 1, timescales: one leaky-integrator unit (eq. 3) and MTRNN_a's IO, Cf, Cs while it speaks."""

from __future__ import annotations

import math

import numpy as np

from model.encoding.utterance import PHONEMES
from server.lessons import DECODE_THRESHOLD, rounded
from server.services.corpus import Corpus
from server.services.errors import Invalid
from server.services.models import ModelRegistry

TABLE1_TAUS = {"IO": 2.0, "Cf": 5.0, "Cs": 70.0}  # MTRNN_a, Table 1


def leaky_pulse(tau: float, steps: int = 120, onset: int = 10, width: int = 10) -> dict:
    """One leaky-integrator unit (eq. 3 with one input) answering a pulse of `width` steps.

    z_t = (1 - 1/tau) z_{t-1} + (1/tau) x_t, x = 1 during the pulse and 0 otherwise. Returned for
    `tau` and for the three timescales of MTRNN_a (Table 1), with the half-life of the decay.
    """
    if not (math.isfinite(tau) and 1.0 <= tau <= 200.0):
        raise Invalid(f"tau must be between 1 and 200 (1 = no memory), got {tau}")
    x = np.zeros(steps)
    x[onset : onset + width] = 1.0

    def integrate(t: float) -> np.ndarray:
        z = np.zeros(steps)
        for k in range(1, steps):
            z[k] = (1.0 - 1.0 / t) * z[k - 1] + x[k] / t  # eq. (3)
        return z

    z = integrate(tau)
    half_life = math.inf if tau == 1.0 else math.log(0.5) / math.log(1.0 - 1.0 / tau)
    end = onset + width - 1
    return {
        "tau": tau,
        "input": rounded(x, 3),
        "z": rounded(z),
        "peak": round(float(z.max()), 4),
        "half_life_steps": None if tau == 1.0 else round(half_life, 2),
        "left_after_20_steps": round(float(z[min(end + 20, steps - 1)] / max(z[end], 1e-12)), 4),
        "references": {name: rounded(integrate(t)) for name, t in TABLE1_TAUS.items()},
    }


def _layer_speed(y: np.ndarray) -> float:
    """Mean |y_t - y_{t-1}| over units and steps: how fast a layer's activity changes."""
    return float(np.abs(np.diff(y, axis=0)).mean()) if len(y) > 1 else 0.0


def timescale_activity(corpus: Corpus, models: ModelRegistry, rid: str) -> dict:
    """MTRNN_a's IO, Cf and Cs activity while it speaks about one corpus recording."""
    entry = corpus.entry(rid)
    lm = models.served
    trace = lm.model.activity_trace(entry.proprioception, entry.vision, lm.lexicon)
    a = trace.auditory
    winners = a.io.argmax(axis=1)
    strong = a.io[np.arange(len(a.io)), winners] >= DECODE_THRESHOLD
    cfg = lm.model.config.auditory
    return {
        "id": rid,
        "model": lm.name,
        "expected": entry.utterance,
        "said": trace.description.text,
        "phonemes": trace.description.phonemes,
        "steps": len(a.io),
        "phoneme_labels": list(PHONEMES),
        "phoneme_at": [PHONEMES[w] if s else "" for w, s in zip(winners, strong, strict=True)],
        "layers": {
            "IO": {"tau": cfg.tau_io, "y": rounded(a.io.T, 3), "speed": round(_layer_speed(a.io), 5)},
            "Cf": {"tau": cfg.tau_cf, "y": rounded(a.cf.T, 3), "speed": round(_layer_speed(a.cf), 5)},
            "Cs": {"tau": cfg.tau_cs, "y": rounded(a.cs.T, 3), "speed": round(_layer_speed(a.cs), 5)},
        },
    }
