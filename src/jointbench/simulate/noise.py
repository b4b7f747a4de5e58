"""Marker noise model shared by every simulated study."""

from __future__ import annotations

import numpy as np

__all__ = ["isotropic_noise"]


def isotropic_noise(rng: np.random.Generator, shape: tuple[int, ...], sd_mm: float) -> np.ndarray:
    """Error vectors with uniformly distributed directions and normal magnitudes.

    Paper A §5.1: "The directions of the error vectors were uniformly distributed, and the
    magnitudes of the random errors were normally distributed with standard deviations of
    0.5, 1.0, and 2.0 mm." Paper B §3.1 uses the same model at 1.0 mm. The magnitude is drawn
    from N(0, sd_mm); its sign only flips an already uniform direction. The RMS length of the
    error vector is therefore ``sd_mm`` and each coordinate has SD ``sd_mm / sqrt(3)``.

    Parameters
    ----------
    rng : the generator to draw from.
    shape : leading shape, e.g. ``(n_frames, n_markers)``; the result is ``(*shape, 3)`` [mm].
    sd_mm : standard deviation of the error magnitude [mm].
    """
    directions = rng.normal(size=(*shape, 3))
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    magnitudes = rng.normal(0.0, sd_mm, size=shape)
    return directions * magnitudes[..., None]
