"""The centre's stated precision against a literal transcription of the formulas in
:mod:`jointbench.estimators.centre_precision`'s docstring, on noisy data whose markers all lie
far from the answer (so every marker counts in the statement)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_center_estimators import CENTER, M_SET, moving_markers, spiral_rotations
from test_center_known_answers import _noisy_cap

import jointbench
from jointbench.estimators import precision
from jointbench.simulate.noise import isotropic_noise


def _stated_by_the_formulas(markers: np.ndarray, centre: np.ndarray, s2: float):
    """``(s / sqrt(lambda_min(F_s)), v' (F - F_s) v / lambda_min(F_s), F_s)``: ``F`` the scatter of
    the unit directions from ``centre``, ``F_s`` it less ``(N - 1) (s^2 / r_p^2) (I - m m')``
    per marker, ``v`` the least eigenvector of ``F_s``."""
    n_frames = markers.shape[0]
    signal, noise = np.zeros((3, 3)), np.zeros((3, 3))
    for p in range(markers.shape[1]):
        offsets = markers[:, p] - centre
        distances = np.linalg.norm(offsets, axis=1)
        units = offsets / distances[:, None]
        centred = units - units.mean(axis=0)
        mean_direction = units.sum(axis=0) / np.linalg.norm(units.sum(axis=0))
        share = (n_frames - 1) * s2 / distances.mean() ** 2
        tangential = share * (np.eye(3) - np.outer(mean_direction, mean_direction))
        signal += centred.T @ centred - tangential
        noise += tangential
    values, vectors = np.linalg.eigh(signal)
    least = vectors[:, 0]
    return math.sqrt(s2 / values[0]), float(least @ noise @ least) / values[0], signal


def _corrected_information(markers: np.ndarray, centre: np.ndarray, s2: float) -> np.ndarray:
    """``F_s`` ``(3, 3)`` about ``centre`` (:func:`_stated_by_the_formulas`)."""
    return _stated_by_the_formulas(markers, centre, s2)[2]


@pytest.mark.parametrize(("seed", "rom_deg"), [(1, 25.0), (2, 12.0)])
def test_centre_sd_and_noise_share_are_those_of_the_formulas(seed, rom_deg):
    markers = _noisy_cap(seed, rom_deg=rom_deg)
    result = jointbench.fit_center(markers, method="IS")
    s2 = result.diagnostics["support_rigid_residual_mm"] ** 2 / 3.0
    sd, share, _ = _stated_by_the_formulas(markers, np.asarray(result.center), s2)
    assert result.diagnostics["center_sd_mm"] == pytest.approx(sd, rel=1e-9)
    assert result.diagnostics["center_sd_noise_share"] == pytest.approx(share, rel=1e-9)


@pytest.mark.parametrize("seed", [1, 2])
def test_centre_fit_ratio_is_the_radial_residuals_over_their_degrees_of_freedom(seed):
    """``center_fit_ratio`` is ``sum e^2 / (P (N - 1) s^2)``: the radial residuals
    ``e = |x - c| - r_p`` about the answer, ``r_p`` each marker's mean distance (one per marker
    profiled out of its ``N`` residuals)."""
    markers = _noisy_cap(seed)
    result = jointbench.fit_center(markers, method="IS")
    s2 = result.diagnostics["support_rigid_residual_mm"] ** 2 / 3.0
    distances = np.linalg.norm(markers - np.asarray(result.center), axis=-1)
    squares = np.sum((distances - distances.mean(axis=0)) ** 2)
    n_frames, n_markers = distances.shape
    expected = squares / (n_markers * (n_frames - 1) * s2)
    assert result.diagnostics["center_fit_ratio"] == pytest.approx(expected, rel=1e-9)


def test_centre_sd_matches_the_scatter_of_the_answers_over_seeds():
    """Over 200 seeds of paper A's M set on a 25 degree cap with 0.5 mm noise, the geometric
    fit's error along the least determined direction (the noise-free scatter's least
    eigenvector) has the RMS of the stated SD, to within 15 % (its own spread is about 5 %)."""
    clean = moving_markers(spiral_rotations(25.0), M_SET, CENTER)
    units = (clean - CENTER) / np.linalg.norm(clean - CENTER, axis=-1, keepdims=True)
    centred = units - units.mean(axis=0)
    least = np.linalg.eigh(np.einsum("kpi,kpj->ij", centred, centred))[1][:, 0]
    rng = np.random.default_rng(123)
    errors, sds = [], []
    for _ in range(200):
        result = jointbench.fit_center(
            clean + isotropic_noise(rng, clean.shape[:2], 0.5), method="IS"
        )
        errors.append(float((np.asarray(result.center) - CENTER) @ least))
        sds.append(result.diagnostics["center_sd_mm"])
    ratio = math.sqrt(np.mean(np.square(errors))) / math.sqrt(np.mean(np.square(sds)))
    assert 0.85 < ratio < 1.15


def _radial_squares(markers: np.ndarray, centre: np.ndarray) -> tuple[float, float]:
    """The radial residuals' sum of squares [mm^2] and of fourth powers [mm^4] about
    ``centre``, each marker's mean distance profiled out."""
    distances = np.linalg.norm(markers - centre, axis=-1)
    residuals = distances - distances.mean(axis=0)
    return float(np.sum(residuals**2)), float(np.sum(residuals**4))


def test_centre_offset_is_the_excess_residual_along_the_best_determined_direction():
    """LS on a 15 degree cap with 1 mm noise is pulled millimetres off the spheres' centre; its
    ``center_offset_mm`` is ``sqrt((sum e^2 - P (N - 1) s^2) / lambda_max(F_s))``."""
    markers = _noisy_cap(4, rom_deg=15.0, noise_mm=1.0)
    result = jointbench.fit_center(markers, method="LS")
    centre = np.asarray(result.center)
    s2 = result.diagnostics["support_rigid_residual_mm"] ** 2 / 3.0
    squares, _ = _radial_squares(markers, centre)
    n_frames, n_markers = markers.shape[:2]
    excess = squares - n_markers * (n_frames - 1) * s2
    largest = np.linalg.eigvalsh(_corrected_information(markers, centre, s2))[-1]
    assert excess > 0.0
    expected = math.sqrt(excess / largest)
    assert result.diagnostics["center_offset_mm"] == pytest.approx(expected, rel=1e-9)


def test_centre_fit_p_value_floors_the_residuals_kurtosis_at_a_normal_ones():
    """Uniform noise leaves radial residuals lighter-tailed than normal: the lack of fit's z,
    ``(ratio - 1) / sqrt((2 + max(kurtosis, 0)) (1 / dof + 1 / noise_dof))``, must not take
    their negative excess kurtosis for extra precision."""
    clean = moving_markers(spiral_rotations(25.0), M_SET, CENTER) + 300.0
    rng = np.random.default_rng(9)
    markers = clean + rng.uniform(-0.6, 0.6, size=clean.shape)
    result = jointbench.fit_center(markers, method="IS")
    s2 = result.diagnostics["support_rigid_residual_mm"] ** 2 / 3.0
    squares, fourths = _radial_squares(markers, np.asarray(result.center))
    n_frames, n_markers = markers.shape[:2]
    dof = n_markers * (n_frames - 1)
    kurtosis = n_markers * n_frames * fourths / squares**2 - 3.0
    assert kurtosis < -0.5
    ratio = squares / (dof * s2)
    noise_dof = precision.rigid_dof(n_markers, n_frames)
    z = (ratio - 1.0) / math.sqrt(2.0 * (1.0 / dof + 1.0 / noise_dof))
    expected = 0.5 * math.erfc(z / math.sqrt(2.0))
    assert result.diagnostics["center_fit_p_value"] == pytest.approx(expected, rel=1e-9)


def test_centre_step_in_sds_is_its_mahalanobis_distance_to_the_geometric_fit():
    """LS on a 15 degree cap with 1 mm noise: ``center_step_mm`` is the distance to the spheres'
    own centre (IS's answer, by the simplex) and ``center_step_sds`` that distance in the
    answer's SDs, ``sqrt(d' F_s d / s^2)`` with ``F_s`` about the answer."""
    markers = _noisy_cap(4, rom_deg=15.0, noise_mm=1.0)
    result = jointbench.fit_center(markers, method="LS")
    centre = np.asarray(result.center)
    step = centre - np.asarray(jointbench.fit_center(markers, method="IS").center)
    s2 = result.diagnostics["support_rigid_residual_mm"] ** 2 / 3.0
    sds = math.sqrt(step @ _corrected_information(markers, centre, s2) @ step / s2)
    assert result.diagnostics["center_step_mm"] == pytest.approx(np.linalg.norm(step), rel=1e-2)
    assert result.diagnostics["center_step_sds"] == pytest.approx(sds, rel=1e-2)
