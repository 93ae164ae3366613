"""The live computations behind the seven lessons (web/lessons/), one module per lesson.

Every number a lesson shows is computed from the served models and the corpus, on request:

1. timescales    eq. (3) on one unit, and MTRNN_a's IO, Cf, Cs activity
2. speaking      text -> ARPAbet -> Gaussian spikes -> softmax (eqs. 18-21) -> decoder
3. seeing        the vision pipeline's stages on one frame (Fig. 7)
4. feeling       one action on four objects, and why touch alone is ambiguous
5. abstracting   the experiment of 3.2.2 run live (a job kind), and the stored sweeps
6. associating   the three Csc spaces (Fig. 10) and muting one modality
7. generalising  training vs novel scenes for one model

A lesson keeps no state: it takes the app's services (corpus, model registry, survey, jobs).
"""

from __future__ import annotations

from typing import Any

import numpy as np

LESSONS: tuple[tuple[str, str], ...] = (
    ("timescales", "1. Timescales"),
    ("speaking", "2. Speaking in phonemes"),
    ("seeing", "3. Seeing"),
    ("feeling", "4. Feeling"),
    ("abstracting", "5. Abstracting"),
    ("associating", "6. Associating"),
    ("generalising", "7. Generalising"),
)
DECODE_THRESHOLD = 0.3  # the decoder's default (model.encoding.utterance)


def rounded(values: Any, digits: int = 4) -> Any:
    """A numpy array (or scalar) as nested lists of rounded floats, for JSON."""
    return np.round(np.asarray(values, dtype=np.float64), digits).tolist()
