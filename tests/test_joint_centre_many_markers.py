"""Joint centres of clusters of many markers over few frames (dense surface markers): the
checked call's memory grows at most linearly in the markers.

The model test's kurtosis reads the fourth moments of a rigid fit's residuals, a sum over the
``n^2`` blocks of the fit's hat matrix (:func:`jointbench.estimators.hjc._residual_moments`),
taken in closed form instead of over the blocks kept; the verdict's frame-0 spread takes the
cluster's singular values without its ``(n, n)`` left singular vectors.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from peak_memory import peak_growth_mb

from jointbench.estimators import hjc

#: Markers whose hat matrix, kept as blocks ``(n, n, 3, 3)``, would take 618 MB, and whose
#: left singular vectors ``(n, n)`` 69 MB.
MANY_MARKERS = 3000


def _fourth_moment(blocks: np.ndarray) -> np.ndarray:
    """``tr(X)^2 + 2 tr(X X')`` of each 3x3 block ``(..., 3, 3)``."""
    return np.trace(blocks, axis1=-2, axis2=-1) ** 2 + 2.0 * np.einsum(
        "...ij,...ij->...", blocks, blocks
    )


def _explicit_moments(body: np.ndarray) -> tuple[float, float]:
    """``(G, F)`` of :func:`hjc._residual_moments` from the blocks of ``I - H`` kept, each
    pair's term summed exactly (``math.fsum``)."""
    n = len(body)
    residual = -hjc._marker_gains(body, body)
    residual[np.arange(n), np.arange(n)] += np.eye(3)
    own = math.fsum(_fourth_moment(residual[np.arange(n), np.arange(n)]))
    squared = np.einsum("jiab,jiac->jibc", residual, residual)
    return own, math.fsum(_fourth_moment(squared).ravel()) / 3.0


@pytest.mark.parametrize(
    "body",
    [
        np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 80.0, 0.0]]),
        np.random.default_rng(1).normal(scale=60.0, size=(4, 3)) + np.array([300.0, -200.0, 900.0]),
        np.random.default_rng(2).normal(scale=60.0, size=(12, 3)),
        # Nearly collinear: the inertia's least eigenvalue 1e-12 of its largest.
        np.random.default_rng(3).normal(size=(6, 3)) * [100.0, 1e-4, 1e-4],
        # Past the markers whose pairs are summed one by one: the closed form.
        np.random.default_rng(5).normal(scale=60.0, size=(hjc._PAIRED_MARKERS + 1, 3)),
        np.random.default_rng(4).normal(scale=[100.0, 70.0, 30.0], size=(400, 3)),
    ],
)
def test_the_residual_moments_are_the_sums_over_the_hats_blocks(body):
    """The sums, pair by pair on a few markers and in closed form on more, are the sum over
    every pair of the hat's blocks, to rounding, compiled and as written."""
    own, shared = _explicit_moments(body)
    assert hjc._residual_moments(body) == pytest.approx((own, shared), rel=1e-13)
    if len(body) <= hjc._PAIRED_MARKERS + 1:
        written = hjc._residual_moments.__wrapped__(body)
        assert written == pytest.approx((own, shared), rel=1e-13)


@pytest.mark.parametrize(
    ("setup", "call", "most_mb"),
    [
        (
            """
            import numpy as np
            from jointbench.estimators import hjc
            body = np.random.default_rng(0).normal(scale=60.0, size=(n, 3))
            """,
            "hjc._residual_moments(body)",
            MANY_MARKERS**2 * 72 / 2**20 / 16,
        ),
        (
            """
            import numpy as np
            from jointbench.estimators import support
            markers = np.random.default_rng(0).normal(scale=60.0, size=(1, 4, n, 3))
            """,
            "support._poses_defined(markers)",
            MANY_MARKERS**2 * 8 / 2**20 / 4,
        ),
    ],
    ids=["residual moments", "frame-0 spread"],
)
def test_many_markers_are_tested_without_a_quadratic_array(setup, call, most_mb):
    """3,000 markers, in a process of its own: the peak memory grows by far less than an array
    of ``n^2`` entries (the hat's blocks; the left singular vectors) would take."""
    assert peak_growth_mb(setup, call, 30, MANY_MARKERS) < most_mb


#: Markers per cluster of the checked calls, whose hat matrices kept as blocks would take
#: 154 MB.
CHECKED_MARKERS = 1500


def test_a_checked_joint_centre_of_many_markers_keeps_no_quadratic_array():
    """Every joint-centre method's checked call (fit, screen, verdict, precision and model
    test) on two clusters of 1,500 markers over 5 frames, in a process of its own: the peak
    memory grows by far less than one cluster's hat matrix kept as blocks would take."""
    setup = """
        import numpy as np
        import jointbench
        from jointbench.estimators import registry
        from jointbench.geometry import rotation_matrix

        rng = np.random.default_rng(0)
        turns = np.linspace(0.0, 1.0, 5)[:, None] * [0.3, 0.2, 0.1]
        body = rng.normal(scale=60.0, size=(2, n, 3)) + [[[0.0, 0.0, 200.0]], [[0.0, 0.0, -200.0]]]
        proximal = body[0] @ rotation_matrix(turns).transpose(0, 2, 1)
        distal = body[1] @ rotation_matrix(-turns).transpose(0, 2, 1)
        proximal = proximal + rng.normal(scale=0.3, size=proximal.shape)
        distal = distal + rng.normal(scale=0.3, size=distal.shape)
        methods = registry.methods("joint_center")
        """
    call = """
        for method in methods:
            jointbench.fit_joint_center(proximal, distal, method, artefacts="warn")
        """
    hat_mb = CHECKED_MARKERS**2 * 72 / 2**20
    assert peak_growth_mb(setup, call, 30, CHECKED_MARKERS) < hat_mb / 8
