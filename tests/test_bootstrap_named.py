"""A bootstrap that cannot support an interval names what it refitted: the recording and the
method, so that of several methods fitted at once the message says which one failed."""

from __future__ import annotations

import numpy as np
import pytest
from test_programming_errors import NAME, _on_repeated_frames, _prepared, _stated, registered

from jointbench.uncertainty import bootstrap

__all__ = ["registered"]  # the fixture, used by name


def test_the_refusal_names_what_was_refitted():
    with pytest.raises(ValueError, match=r"^hip LS: bootstrap: 10 of 10 refits failed"):
        bootstrap(lambda resamples: [None] * len(resamples), 50, n_resamples=10, label="hip LS")


def test_a_recordings_bootstrap_names_the_recording_and_the_method(registered):
    # Resamples repeat frames, the main fit's frames are distinct: only the refits fail.
    registered(_on_repeated_frames(_stated))
    prepared = _prepared()
    assert prepared.fit(NAME).result.converged
    with pytest.raises(ValueError, match="refits failed") as raised:
        prepared.fit(NAME, n_bootstrap=20, seed=0)
    message = str(raised.value)
    assert message.startswith(f"{prepared.recording.source}: center {NAME}: bootstrap: "), message
    assert np.isfinite(prepared.fit("LS", n_bootstrap=20, seed=0).bootstrap.covariance()).all()


def test_a_bootstrap_without_a_label_is_refused_before_it_refits():
    refitted = []

    def statistic(resamples):
        refitted.append(len(resamples))
        return [None] * len(resamples)

    with pytest.raises(TypeError, match="label"):
        bootstrap(statistic, 50, n_resamples=10)
    for label in ("", "  ", None):
        with pytest.raises(ValueError, match="label must name what is refitted"):
            bootstrap(statistic, 50, n_resamples=10, label=label)
    assert not refitted


def test_a_refused_bootstrap_says_why_its_refits_failed():
    """Refits that cannot answer give their reasons; the refusal counts each kind and quotes
    the commonest, not a guess at the cause."""

    def statistic(indices):
        return [
            "did not converge: the markers' pose fit stopped after 100 re-estimations"
            if row % 3
            else (np.zeros(3) if row % 2 else "failed: too few frames")
            for row in range(len(indices))
        ]

    with pytest.raises(ValueError) as raised:
        bootstrap(statistic, 40, n_resamples=12, label="trial SCoRE")
    message = str(raised.value)
    assert message.startswith("trial SCoRE: bootstrap: 10 of 12 refits failed (8 did not "), message
    assert "2 failed; e.g. did not converge: the markers' pose fit stopped after 100" in message
