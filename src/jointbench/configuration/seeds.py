"""Seeds derived from (study, condition, trial), so any trial regenerates alone."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping

import numpy as np

__all__ = ["trial_rng", "trial_seed"]


def trial_seed(base_seed: int, study: str, condition: Mapping[str, object], trial: int) -> int:
    """A 64-bit seed that depends only on its arguments, not on job order or ``-j``.

    The condition is serialised with sorted keys, so dict order does not matter; numbers are
    written with ``repr`` semantics by JSON, so ``1.0`` and ``1`` differ (conditions come from
    one config and keep their types).
    """
    key = json.dumps(
        {"base": int(base_seed), "study": study, "condition": dict(condition), "trial": int(trial)},
        sort_keys=True,
    )
    return int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "little")


def trial_rng(
    base_seed: int, study: str, condition: Mapping[str, object], trial: int
) -> np.random.Generator:
    """``numpy.random.Generator`` seeded by :func:`trial_seed`."""
    return np.random.default_rng(trial_seed(base_seed, study, condition, trial))
