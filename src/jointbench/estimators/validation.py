"""Input checks shared by the estimators. Every failure is a ``ValueError`` naming the problem."""

from __future__ import annotations

import numpy as np

__all__ = ["check_markers", "check_moves", "check_not_collinear", "check_same_frames"]


def check_markers(
    markers: object, *, min_frames: int = 1, min_markers: int = 1, name: str = "markers"
) -> np.ndarray:
    """Return ``markers`` as a float64 ``(n_frames, n_markers, 3)`` array, or raise ``ValueError``.

    Checks the shape, finiteness and the minimum numbers of frames and markers a method needs.
    """
    array = np.asarray(markers, dtype=float)
    if array.ndim != 3 or array.shape[-1] != 3:
        raise ValueError(f"{name} must be shaped (n_frames, n_markers, 3), got shape {array.shape}")
    if not np.isfinite(array).all():
        bad = np.argwhere(~np.isfinite(array))[0]
        raise ValueError(
            f"{name} contains NaN or inf (first at frame {bad[0]}, marker {bad[1]}); "
            "drop or fill gaps before fitting"
        )
    n_frames, n_markers, _ = array.shape
    if n_frames < min_frames:
        raise ValueError(f"{name} has {n_frames} frames; this method needs at least {min_frames}")
    if n_markers < min_markers:
        raise ValueError(
            f"{name} has {n_markers} markers; this method needs at least {min_markers}"
        )
    return array


def check_moves(markers: np.ndarray, *, name: str = "markers", tol_mm: float = 1e-9) -> None:
    """Raise ``ValueError`` when no marker moves (every trajectory is a single point)."""
    # ndarray methods, not np.max: these checks run on every fit, and the fast closed-form
    # estimators take tens of microseconds, of which NumPy's Python-level wrappers were a tenth.
    first = markers[0]
    spread = float(np.abs(markers - first).max())
    if spread <= tol_mm * max(1.0, float(np.abs(first).max())):
        raise ValueError(f"{name} do not move: every marker stays at one point in every frame")


def check_not_collinear(markers: np.ndarray, *, name: str = "markers") -> None:
    """Raise ``ValueError`` when the markers of some frame are (nearly) collinear.

    A rigid-body pose needs three non-collinear markers: the second singular value of the
    centred cluster must not vanish relative to the first.
    """
    centred = markers - markers.mean(axis=1, keepdims=True)
    singular = np.linalg.svd(centred, compute_uv=False)
    ratio = singular[:, 1] / np.maximum(singular[:, 0], np.finfo(float).tiny)
    if np.any(ratio < 1e-6):
        frame = int(np.argmin(ratio))
        raise ValueError(
            f"{name} are collinear in frame {frame}: a rigid-body pose needs three "
            "non-collinear markers"
        )


def check_same_frames(first: np.ndarray, second: np.ndarray) -> None:
    """Raise ``ValueError`` when two segments were not recorded over the same frames."""
    if first.shape[0] != second.shape[0]:
        raise ValueError(
            f"proximal and distal markers have {first.shape[0]} and {second.shape[0]} frames; "
            "they must share frames"
        )
