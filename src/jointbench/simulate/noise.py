"""Marker noise model shared by every simulated study."""

from __future__ import annotations

import pickle
from collections import OrderedDict
from collections.abc import Sequence

import numpy as np

from jointbench.declared import DeclarationError

__all__ = ["check_noise_level", "isotropic_noise", "largest_noise_mm"]


class _Remembered:
    """Draws by generator state, the least recently used forgotten beyond ``max_bytes``."""

    def __init__(self, max_bytes: int) -> None:
        self.max_bytes = max_bytes
        self.nbytes = 0
        self.draws: OrderedDict[tuple, tuple[np.ndarray, dict]] = OrderedDict()

    def get(self, key: tuple) -> tuple[np.ndarray, dict] | None:
        if key in self.draws:
            self.draws.move_to_end(key)
            return self.draws[key]
        return None

    def put(self, key: tuple, noise: np.ndarray, state: dict) -> None:
        self.draws[key] = (noise, state)
        self.nbytes += noise.nbytes
        while self.nbytes > self.max_bytes:
            self.nbytes -= self.draws.popitem(last=False)[1][0].nbytes


# Paper C's conditions (the first Nt frames of one recording per trial) share their generators,
# so a job that simulates several of them draws each trial's noise once, not once per condition.
_REMEMBERED = _Remembered(max_bytes=128 * 2**20)


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

    The result is read-only. A draw from a generator state seen before returns the noise drawn
    then and leaves the generator where that draw left it, exactly as drawing again would.
    """
    # Pickled, the state is bytes whatever it holds (a Mersenne Twister's holds an array).
    key = (pickle.dumps(rng.bit_generator.state), tuple(shape), float(sd_mm))
    remembered = _REMEMBERED.get(key)
    if remembered is not None:
        noise, state = remembered
        rng.bit_generator.state = state
        return noise
    noise = _draw(rng, shape, sd_mm)
    noise.setflags(write=False)
    _REMEMBERED.put(key, noise, rng.bit_generator.state)
    return noise


def _draw(rng: np.random.Generator, shape: tuple[int, ...], sd_mm: float) -> np.ndarray:
    directions = rng.normal(size=(*shape, 3))
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    magnitudes = rng.normal(0.0, sd_mm, size=shape)
    return directions * magnitudes[..., None]


def largest_noise_mm(markers_mm: np.ndarray) -> float:
    """The largest marker noise a study may simulate [mm]: the distance from the joint centre of
    the farthest of ``markers_mm`` ``(..., 3)`` [mm, relative to the centre].

    Noise whose RMS length exceeds every marker's distance from the joint scatters each marker
    over a cloud wider than the whole body segment it is on: no trial then holds information on
    a centre or an axis, and far beyond (``1e200`` mm, a typo) the fits' arithmetic overflows.
    Real marker noise, from a fraction of a millimetre (cameras) to a few centimetres
    (soft-tissue artefact), stays well below the bound of any marker set.
    """
    return float(np.linalg.norm(np.reshape(markers_mm, (-1, 3)), axis=-1).max())


def check_noise_level(
    name: str, noise_mm: float, markers_mm: np.ndarray, markers_names: Sequence[str]
) -> None:
    """Raise :class:`~jointbench.declared.DeclarationError` at ``name`` and the fields
    ``markers_names`` that hold ``markers_mm`` (the bound is theirs as much) when ``noise_mm``
    is above :func:`largest_noise_mm` of ``markers_mm``."""
    bound = largest_noise_mm(markers_mm)
    if noise_mm > bound:
        raise DeclarationError(
            (name,),
            f"must be <= {bound:g} mm (the farthest marker's distance from the joint centre: "
            f"noise beyond the whole segment's size measures nothing), got {noise_mm!r}",
            [(markers,) for markers in markers_names],
        )
