"""Axis-of-rotation estimators of Chang & Pollard (2007), paper B §2: planar, radial, combined.

All three take the moving segment's markers in the reference segment's frame,
``(n_frames, n_markers, 3)`` [mm], and return an :class:`AxisResult`.

Model (paper B eqs. 1–12). The axis is the line through a point ``m`` with unit direction ``n``.
Marker ``p`` at frame ``k`` is ``v = v_k^p``; ``u = v - mean_k v^p`` is its offset from its own
trajectory centroid.

* planar cost (eqs. 2–8), best-fitting parallel planes: ``f_p(n) = n' S n``,
  ``S = sum_p sum_k u u'`` (3, 3) [mm^2]. This is Gamage & Lasenby's (2002) axis cost.
* radial cost (eqs. 9–11), best-fitting coaxial cylinders through ``m``:
  ``f_r(n) = sum_p sum_k (|(I - n n') (v - m)| - r_p)^2`` with the radius profiled out,
  ``r_p = mean_k |(I - n n') (v - m)|`` (eq. 11).
* combined cost (eq. 12), best-fitting circles: ``f = f_p + f_r``.

Point on the axis. ``m`` is not searched: it is the NM sphere-fit centre of paper A (Chang &
Pollard's constrained least squares, the many-trial form of
:func:`jointbench.estimators.sphere.fit_nm`, which agrees with it to ~1e-9 mm), as in paper B
§2.4 and §4 ("provided an adequate CoR location to use in the optimization without
refinement"). The axis passes through ``m`` by construction, so ``m`` is its own foot on the
axis and is what ``AxisResult.point`` returns, for all three methods (the planar cost does not
use ``m``; its line is still anchored there). For a near-pure hinge the sphere fit is poorly
determined *along* the axis, so ``m`` may lie far from the markers;
``diagnostics["centroid_foot"]`` is the point of the axis closest to the markers' centroid.

The checked call states how far ``m`` may lie from the axis, across it (where along the axis a
point lies does not matter): ``diagnostics["axis_point_covariance_mm2"]`` ``(3, 3)`` [mm^2],
rank 2 in the plane normal to the axis, and ``diagnostics["axis_point_sd_mm"]``, the SD along
its least determined direction across the axis; above
:data:`jointbench.estimators.results.MAX_AXIS_POINT_SD_MM` the status says the point is not
determined, whatever its direction's SD (:func:`_point_covariance`). ``m`` is the same point
for the three costs, so one model states it: the circles of the combined cost (eq. 12), the
only one of the three that places a line as well as orienting it (the planar cost has no
point; the radial cost's direction is the least determined of the three, and ``m``, fitted by
the sphere, does not move with it). Its Hessian gives the line's tilt and shift at the
markers jointly; the point moves by the shift plus the tilt times its height ``h`` along the
axis from the markers' centroid, so a small direction SD still leaves a point hundreds of
millimetres along a short arc's axis (where the sphere fit puts ``m``) tens of millimetres
off; and how far ``m`` lies from that cost's minimum (its Newton step, carried to ``h``) is
added as a bias (:func:`jointbench.estimators.precision.point_covariance`). The cost is taken
at the line through ``m`` along the planar eigenvector, for the combined answer at its own
line: a radial answer degrees off the axis still passes through ``m``, and expanding about it
would carry that tilt to ``h`` as if ``m`` moved with it. The covariance is first order; for
the combined answer, where under the support verdict's noise the noise's own term in the
combined cost's curvature is not below what it leaves of it
(:func:`jointbench.estimators.precision.noise_share`, the radial residuals' term derived at
:func:`_radial_derivatives`), the point is said not to be determined: on a short noisy arc the
cost, exact in its Hessian, can then rise to the true line by a few residual variances where
its curvature puts it at tens. On swings of 3-90 degrees (``tests/test_axis_point_sd.py``) the
squared Mahalanobis distance of the ``ok`` answers' points from the axis averages about 2, as a
calibrated 2-D statement's should (the README gives the counts).

Search (paper B §3): MATLAB's ``fminsearch`` (Nelder–Mead, Lagarias et al. 1998) as
re-implemented in :mod:`jointbench.numerics.simplex`, from ten starting directions: one vertex
of each antipodal pair of a regular dodecahedron,
``(±1,±1,±1)``, ``(0,±1/φ,±φ)``, ``(±1/φ,±φ,0)``, ``(±φ,0,±1/φ)`` with ``φ`` the golden ratio,
normalised; of each pair the vertex whose first non-zero coordinate is positive (the costs are
even in ``n``). The lowest final cost over the ten wins; ``converged`` is the winning start's
own flag. Tolerances are ``fminsearch``'s defaults, ``TolX = TolFun = 1e-4`` and at most
``200 * n_params`` iterations and evaluations; the paper states no other values.

Parameterisation (``parameterisation="angles"``, the default): the direction is searched as two
spherical angles, MATLAB ``cart2sph``'s azimuth and elevation,
``n = (cos el cos az, cos el sin az, sin el)``, each start converted to its angles. Searching an
unnormalised 3-vector ``x`` with the cost evaluated at ``x / |x|`` (``parameterisation="vector"``,
the literal reading of "fminsearch over ``n``") is ill-posed: the cost is constant along every
ray, so the minimiser is a half-line, not a point, and the simplex drifts along it. On 30 noisy
hinge trials (10 starts each) the final ``|x|`` ranged from 0.003 to 4e17 (48 of 300 runs above
2, 134 below 0.5); since ``TolX`` is absolute, the angular precision at convergence then varies
by orders of magnitude (about 2 degrees at ``|x| = 0.003``). With two angles the minimum is
isolated, ``TolX`` is in radians (scaled by ``cos el`` for the azimuth), the simplex has three
vertices and the search needs about half the evaluations. The angles are singular only
at the poles ``±z``; the map is smooth there (a direction near a pole is reached with a small
``|el - ±90°|`` at any azimuth), so the search still converges, with the azimuth ill-determined.
fminsearch's initial simplex scales each non-zero angle by 1.05 (steps of 1–4 degrees for these
starts) and sets a zero one to 0.00025 rad, as it would for the paper's MATLAB code.

The planar optimum is also the eigenvector of the smallest eigenvalue of ``S`` (Gamage &
Lasenby's closed form); the planar method nevertheless runs the search, as the paper did, and
reports the closed-form eigenvector in ``diagnostics["eigenvector"]`` for comparison.

Where the costs are degenerate:

* planar: ``S`` must have a unique smallest eigenvalue. It does not when every marker moves
  along one line (a tiny RoM), or when the markers all lie on the axis. Rotation about a second
  axis adds variance along the FE axis and the normal can flip to the markers' radial direction
  (paper B Fig. 2b).
* radial: for a pure hinge a tilt ``t`` of the axis about ``m`` changes a marker's distance from
  it, to first order, only in proportion to the marker's offset ``h_p`` along the axis from
  ``m``; when every marker's circle lies in the plane through ``m`` normal to the axis
  (``h_p = 0``) ``f_r`` grows like ``t^4`` and the minimum is very flat. Conversely, when ``m``
  is far along the axis from the markers (``|h_p|`` much larger than the arcs, as the sphere fit
  of a noise-free pure hinge may return, its centre being undetermined along the axis) the
  markers' short arcs lie close to many cylinders through ``m`` and the search is trapped in
  local minima far from the axis. Pass ``point`` to fix ``m`` in such cases.
* combined: inherits the planar cost's curvature in every direction, so its minimum is
  isolated whenever the planar one is; but with ``m`` far along the axis the radial term's
  local minima can still capture all ten starts (a test shows a noise-free pure hinge whose NM
  centre lands 1.1 m away and whose combined search ends 12 degrees off, the true axis costing
  zero).

The checked call (:func:`jointbench.estimators.registry.get`, ``jointbench.fit_axis``) adds
the SD of the direction that each cost implies, ``diagnostics["axis_sd_deg"]``, and warns when
it is above :data:`jointbench.estimators.precision.MAX_AXIS_SD_DEG`
(:func:`_direction_sd_deg`): on a short arc the radial cost can leave the axis undetermined
while the rotation is resolved. For the planar cost, whose answer is an eigenvector, it also
warns where the eigen-gap is within the noise's own share of the scatter: the first-order SD
then leaves out the larger part of the error
(:func:`jointbench.estimators.precision.annotate_validity`); for the radial cost, it compares
the answer with the planar eigenvector, an estimate of the same hinge's axis
(:func:`jointbench.estimators.precision.annotate_agreement`). Its self-check also compares the
two minima it has, the ten starts' and the restart's: more than
:data:`jointbench.estimators.precision.AMBIGUOUS_APART_DEG` apart, the other is stated in
``diagnostics["other_minimum"]`` and, where the data cannot tell the two fits apart, the
direction is said to be ambiguous (:func:`_ambiguity_checked`; the radial cost's second
minimum, which the SD cannot see). The other ten starts' minima are not compared: the
registered function keeps only their costs, and the studies' results must not change.

Returned ``direction`` is a unit vector with a canonical sign: its largest-magnitude component
is positive (angular errors are sign-free, :func:`jointbench.geometry.angle_between_lines_deg`).
"""

from __future__ import annotations

import functools
import math
import typing
from collections.abc import Callable
from typing import Literal

import numpy as np

from jointbench.declared import Count, NonNegative, Point
from jointbench.estimators import precision, selfcheck
from jointbench.estimators.batching import isolated, one_trial
from jointbench.estimators.registry import many, register
from jointbench.estimators.results import AxisResult
from jointbench.estimators.sphere import fit_nm  # noqa: F401 (registers NM, used below)
from jointbench.estimators.support import Support
from jointbench.estimators.validation import check_markers, check_moves, prepare_trials
from jointbench.geometry import angle_between_lines_deg
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.reuse import remembered
from jointbench.numerics.simplex import FATOL, XATOL, SimplexResult, advance, lockstep, started
from jointbench.numerics.small import add_outer, symmetric_into

__all__ = [
    "DODECAHEDRON_STARTS",
    "PARAMETERISATIONS",
    "AxisCosts",
    "angles_to_direction",
    "angles_to_directions",
    "canonical_sign",
    "direction_into",
    "direction_to_angles",
    "fit_combined",
    "fit_planar",
    "fit_radial",
    "trial_scatter",
]

_GOLDEN = (1.0 + math.sqrt(5.0)) / 2.0
Parameterisation = Literal["angles", "vector"]
PARAMETERISATIONS = typing.get_args(Parameterisation)
# Fewest frames an axis search takes (registered as each method's claim, checked in _checked).
_MIN_FRAMES = 4


def _dodecahedron_starts() -> np.ndarray:
    """One vertex of each of the ten antipodal vertex pairs of a regular dodecahedron, normalised.

    ``(10, 3)``. Of each pair, the vertex whose first non-zero coordinate is positive.
    """
    g, h = _GOLDEN, 1.0 / _GOLDEN
    vertices = [
        (1.0, 1.0, 1.0),
        (1.0, 1.0, -1.0),
        (1.0, -1.0, 1.0),
        (1.0, -1.0, -1.0),
        (0.0, h, g),
        (0.0, h, -g),
        (h, g, 0.0),
        (h, -g, 0.0),
        (g, 0.0, h),
        (g, 0.0, -h),
    ]
    starts = np.array(vertices)
    starts /= np.linalg.norm(starts, axis=1, keepdims=True)
    starts.setflags(write=False)
    return starts


DODECAHEDRON_STARTS = _dodecahedron_starts()


def direction_to_angles(direction: np.ndarray) -> tuple[float, float]:
    """``(azimuth, elevation)`` [rad] of a direction (3,), as MATLAB's ``cart2sph``."""
    x, y, z = (float(c) for c in direction)
    return math.atan2(y, x), math.atan2(z, math.hypot(x, y))


def angles_to_direction(azimuth: float, elevation: float) -> np.ndarray:
    """Unit direction (3,) ``(cos el cos az, cos el sin az, sin el)``, as MATLAB's ``sph2cart``."""
    c = math.cos(elevation)
    return np.array((c * math.cos(azimuth), c * math.sin(azimuth), math.sin(elevation)))


def angles_to_directions(params: np.ndarray) -> np.ndarray:
    """Vectorised :func:`angles_to_direction`: ``(k, 2)`` [rad] -> unit ``(k, 3)``."""
    azimuth, elevation = params[:, 0], params[:, 1]
    c = np.cos(elevation)
    # Filled column by column: np.stack costs more than the trigonometry for a few directions.
    directions = np.empty((len(params), 3))
    np.multiply(c, np.cos(azimuth), out=directions[:, 0])
    np.multiply(c, np.sin(azimuth), out=directions[:, 1])
    np.sin(elevation, out=directions[:, 2])
    return directions


class AxisCosts:
    """Paper B's planar, radial and combined costs for one data set or many, precomputed.

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) or (n_trials, n_frames, n_markers, 3) [mm], validated,
        or a list of trials of equal shape; each trial's ``S`` is :func:`trial_scatter`'s.
    point : (3,) or (n_trials, 3) [mm], the point ``m`` on each trial's axis (used by the
        radial cost only).

    ``planar``, ``radial`` and ``combined`` take unit directions ``(3,)`` or ``(k, 3)`` and,
    with many trials, the trial of each direction (``trials`` ``(k,)``; trial 0 by default);
    they return the cost(s) [mm^2]. ``planar`` is the quadratic form ``n' S n`` on the
    precomputed ``S``; the radial cost is :func:`_radial_costs`. Each direction's cost is
    computed on its own, the same way whichever trials and directions share the call, so a
    search over many trials follows the path it follows alone.
    """

    def __init__(self, markers: np.ndarray | list[np.ndarray], point: np.ndarray) -> None:
        point = np.asarray(point, dtype=float)
        if isinstance(markers, list):
            trials = [np.asarray(trial, dtype=float) for trial in markers]
            markers = np.stack(trials)
        else:
            markers = np.asarray(markers, dtype=float)
            if markers.ndim == 3:
                markers, point = markers[None], point[None]
            trials = list(markers)
        _, n_frames, n_markers, _ = markers.shape
        self.scatter = np.stack([trial_scatter(trial) for trial in trials])
        self.point = point
        self._markers = markers
        self._shape = (n_markers, n_frames)

    def trial_markers(self, trial: int) -> np.ndarray:
        """The markers ``(N, P, 3)`` [mm] of ``trial``."""
        return self._markers[trial]

    # The radial cost's arrays are made on first use, from the markers as they are then: the
    # planar cost never needs them.
    @functools.cached_property
    def _w(self) -> np.ndarray:
        """Per coordinate, marker-major rows ``(3, n_trials, P N)``: the offsets ``w`` of every
        sample [mm]."""
        offsets = np.transpose(self._markers - self.point[:, None, None, :], (3, 0, 2, 1))
        return np.ascontiguousarray(offsets).reshape(3, len(self.point), -1)

    @functools.cached_property
    def _w_sq(self) -> np.ndarray:
        """``|w|^2`` of every sample ``(n_trials, P N)`` [mm^2]."""
        w = self._w
        return w[0] * w[0] + w[1] * w[1] + w[2] * w[2]

    @staticmethod
    def _trials(directions: np.ndarray, trials: np.ndarray | None) -> np.ndarray:
        return np.zeros(len(directions), dtype=int) if trials is None else np.asarray(trials)

    def planar(self, directions: np.ndarray, trials: np.ndarray | None = None) -> np.ndarray:
        """``f_p = n' S n`` (paper B eq. 8): ``(3,)`` -> scalar array, ``(k, 3)`` -> ``(k,)``."""
        n = np.asarray(directions, dtype=float)
        flat = kernel_array(n.reshape(-1, 3))
        costs = np.empty(len(flat))
        _planar_costs(self.scatter, flat, self._checked_trials(flat, trials), costs)
        return costs.reshape(n.shape[:-1])

    def _checked_trials(self, directions: np.ndarray, trials: np.ndarray | None) -> np.ndarray:
        """The trial of each of ``directions`` ``(k, 3)`` (trial 0 by default) as a kernel's
        ``(k,)`` indices; ``ValueError`` for a trial these costs do not hold."""
        trials = self._trials(directions, trials)
        if not np.issubdtype(trials.dtype, np.integer):
            raise ValueError(f"trials must be integer indices, got {trials.dtype} {trials!r}")
        trials = kernel_array(trials, np.intp)
        n_trials = len(self.scatter)
        if trials.shape != (len(directions),):
            raise ValueError(
                f"trials must be shaped ({len(directions)},), one per direction, got {trials.shape}"
            )
        outside = (trials < -n_trials) | (trials >= n_trials)
        if outside.any():
            raise ValueError(
                f"trial {int(trials[outside][0])} does not exist: these costs hold {n_trials} "
                "trials"
            )
        return trials

    def _radial(self, directions: np.ndarray, trials: np.ndarray, distances: np.ndarray):
        """Radial costs ``(k,)`` of unit directions ``(k, 3)`` in ``trials`` ``(k,)``, and the
        distances into ``distances`` ``(k, P N)`` unless it is ``(0, 0)``."""
        flat = kernel_array(np.reshape(directions, (-1, 3)))
        trials = self._checked_trials(flat, trials)
        costs = np.empty(len(flat))
        _radial_costs(self._w, self._w_sq, flat, trials, self._shape[0], costs, distances)
        return costs

    def radial_distances(self, directions: np.ndarray, trial: int = 0) -> np.ndarray:
        """Distances ``|(I - n n')(v - m)|`` [mm] in ``trial``: ``(..., n_markers, n_frames)``."""
        n = np.asarray(directions, dtype=float)
        k = math.prod(n.shape[:-1])
        distances = np.empty((k, self._w.shape[2]))
        self._radial(n, np.full(k, trial, dtype=np.intp), distances)
        return distances.reshape(*n.shape[:-1], *self._shape)

    def radial(self, directions: np.ndarray, trials: np.ndarray | None = None) -> np.ndarray:
        """``f_r`` with the radii profiled out (paper B eqs. 10–11)."""
        n = np.asarray(directions, dtype=float)
        flat = n.reshape(-1, 3)
        return self._radial(flat, trials, _NO_DISTANCES).reshape(n.shape[:-1])

    def combined(self, directions: np.ndarray, trials: np.ndarray | None = None) -> np.ndarray:
        """``f = f_p + f_r`` (paper B eq. 12)."""
        return self.planar(directions, trials) + self.radial(directions, trials)

    def batch_cost(
        self, method: str, parameterisation: str, trial_of: Callable[[np.ndarray], np.ndarray]
    ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """Cost of a batch of search parameters, ``(k, 2)`` angles or ``(k, 3)`` vectors, whose
        searches ``owners`` ``(k,)`` belong to the trials ``trial_of(owners)``."""
        cost = {"planar": self.planar, "radial": self.radial, "combined": self.combined}[method]
        return _of_parameters(
            lambda directions, owners: cost(directions, trial_of(owners)), parameterisation
        )

    def search_cost(
        self, method: str, parameterisation: str
    ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """:meth:`batch_cost` of one search per trial (``owners`` are the trials), each cost
        computed by the same operations, without the checks of the public costs: for few
        searches, whose every evaluation would pay them (the self-check's restarts)."""
        n_markers = self._shape[0]

        def cost(directions: np.ndarray, trials: np.ndarray) -> np.ndarray:
            directions = kernel_array(directions)
            trials = kernel_array(trials, np.intp)
            if method != "planar":
                radial = np.empty(len(directions))
                _radial_costs(
                    self._w, self._w_sq, directions, trials, n_markers, radial, _NO_DISTANCES
                )
                if method == "radial":
                    return radial
            planar = np.empty(len(directions))
            _planar_costs(self.scatter, directions, trials, planar)
            return planar if method == "planar" else planar + radial

        return _of_parameters(cost, parameterisation)


def _of_parameters(
    cost: Callable[[np.ndarray, np.ndarray], np.ndarray], parameterisation: str
) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """``cost(directions, owners)`` of unit directions ``(k, 3)`` as the cost of search
    parameters ``(k, 2)`` angles or ``(k, 3)`` vectors (module notes); a zero vector costs
    ``inf``."""
    if parameterisation == "angles":
        return lambda params, owners: cost(angles_to_directions(params), owners)

    def cost_vector(params: np.ndarray, owners: np.ndarray) -> np.ndarray:
        norm = np.linalg.norm(params, axis=1)
        zero = norm == 0.0
        value = cost(params / np.where(zero, 1.0, norm)[:, None], owners)
        value[zero] = np.inf
        return value

    return cost_vector


def trial_scatter(markers: np.ndarray) -> np.ndarray:
    """Paper B's ``S`` ``(3, 3)`` [mm^2] of one trial's ``markers`` ``(N, P, 3)`` [mm]
    (:func:`_scatters`), read-only: computed once per array in a checked call, whose fit,
    self-check and statement of precision all read it
    (:func:`jointbench.numerics.reuse.remembered`)."""
    return remembered("planar scatter", markers, _scatter_of)


def _scatter_of(markers: np.ndarray) -> np.ndarray:
    """:func:`_scatters` of one trial ``(N, P, 3)`` [mm], read-only ``(3, 3)`` [mm^2]."""
    scatter = _scatters(kernel_array(markers[None]))[0]
    scatter.setflags(write=False)
    return scatter


@kernel
def _scatters(markers: np.ndarray) -> np.ndarray:
    """Paper B's ``S = sum_p sum_k u u'`` ``(T, 3, 3)`` [mm^2] of each trial of ``markers``
    ``(T, N, P, 3)`` [mm], ``u`` a marker's offset from its trajectory centroid. A compiled
    kernel: summed frame by frame as NumPy's ``mean(axis=0)`` and
    ``np.einsum("kpi,kpj->ij", u, u)`` sum, so ``S`` is theirs to the last bit."""
    n_trials, n_frames, n_markers, _ = markers.shape
    scatter = np.zeros((n_trials, 3, 3))
    centroid = np.empty((n_markers, 3))
    for t in range(n_trials):
        centroid[:] = 0.0
        for k in range(n_frames):
            for p in range(n_markers):
                for i in range(3):
                    centroid[p, i] += markers[t, k, p, i]
        centroid /= n_frames
        sums = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        for k in range(n_frames):
            for p in range(n_markers):
                sums = add_outer(
                    sums,
                    markers[t, k, p, 0] - centroid[p, 0],
                    markers[t, k, p, 1] - centroid[p, 1],
                    markers[t, k, p, 2] - centroid[p, 2],
                )
        symmetric_into(sums, scatter[t])
    return scatter


@kernel
def _height_fourths(markers: np.ndarray, direction: np.ndarray) -> float:
    """``sum_p sum_k (n . u)^4`` [mm^4] of one trial's ``markers`` ``(N, P, 3)`` [mm] along
    the unit ``direction`` ``n`` (3,), ``u`` a marker's offset from its trajectory centroid:
    the planar residuals' fourth powers. A compiled kernel (the offsets as NumPy arrays cost
    most of a long trial's statement of precision)."""
    n_frames, n_markers, _ = markers.shape
    total = 0.0
    for p in range(n_markers):
        mean = 0.0
        for k in range(n_frames):
            mean += _height(markers[k, p], direction)
        mean /= n_frames
        for k in range(n_frames):
            total += (_height(markers[k, p], direction) - mean) ** 4
    return total


@kernel
def _height(point: np.ndarray, direction: np.ndarray) -> float:
    """``n . x`` [mm] of a ``point`` ``x`` (3,) [mm] along ``direction`` ``n`` (3,). A compiled
    kernel."""
    return point[0] * direction[0] + point[1] * direction[1] + point[2] * direction[2]


@kernel
def _planar_costs(
    scatter: np.ndarray, directions: np.ndarray, trials: np.ndarray, costs: np.ndarray
) -> None:
    """Paper B's planar cost ``n' S n`` (eq. 8) of each unit direction ``directions[k]``
    (k, 3) with the scatter ``scatter[trials[k]]`` (T, 3, 3) [mm^2], into ``costs[k]``. A
    compiled kernel: summed as ``np.einsum("ki,kij,kj->k", ...)`` sums it, term by term in
    row-major order, so a cost is the same to the last bit whichever form computed it."""
    for k in range(directions.shape[0]):
        s = scatter[trials[k]]
        total = 0.0
        for i in range(3):
            for j in range(3):
                total += directions[k, i] * s[i, j] * directions[k, j]
        costs[k] = total


# ``_radial_costs`` stores no distances when given this.
_NO_DISTANCES = np.empty((0, 0))


@kernel
def _radial_costs(
    offsets: np.ndarray,
    offsets_sq: np.ndarray,
    directions: np.ndarray,
    trials: np.ndarray,
    n_markers: int,
    costs: np.ndarray,
    distances: np.ndarray,
) -> None:
    """Paper B's radial cost (eqs. 10–11) of each unit direction ``directions[k]`` (k, 3) in
    trial ``trials[k]`` (k,), into ``costs[k]`` [mm^2]; and, unless ``distances`` is
    ``(0, 0)``, each sample's distance from the axis into ``distances[k]`` (k, P N) [mm]. A
    compiled kernel (:mod:`jointbench.numerics.compiled`).

    ``offsets`` (3, T, P N) holds every sample's ``w = v - m`` per coordinate, marker-major;
    ``offsets_sq`` (T, P N) its ``|w|^2``. With ``w`` fixed, a distance needs only ``n . w``:
    ``|(I - n n') w|^2 = |w|^2 - (n . w)^2``. Radii and squared deviations are summed in two
    passes; the one-pass form ``sum d^2 - N sum r_p^2`` cancels catastrophically near an exact
    fit.
    """
    n_samples = offsets.shape[2]
    n_frames = n_samples // n_markers
    distance = np.empty(n_samples)
    for k in range(directions.shape[0]):
        trial = trials[k]
        n0, n1, n2 = directions[k, 0], directions[k, 1], directions[k, 2]
        for j in range(n_samples):
            along = offsets[0, trial, j] * n0 + offsets[1, trial, j] * n1
            along += offsets[2, trial, j] * n2
            squared = offsets_sq[trial, j] - along * along
            # It can round below zero for a sample on the axis itself.
            if squared < 0.0:
                squared = 0.0
            distance[j] = math.sqrt(squared)
        total = 0.0
        for p in range(n_markers):
            radius = 0.0
            for j in range(p * n_frames, (p + 1) * n_frames):
                radius += distance[j]
            radius *= 1.0 / n_frames
            for j in range(p * n_frames, (p + 1) * n_frames):
                deviation = distance[j] - radius
                total += deviation * deviation
        costs[k] = total
        if distances.shape[0]:
            distances[k] = distance


def canonical_sign(direction: np.ndarray) -> np.ndarray:
    """Unit ``direction`` (3,) flipped so that its largest-magnitude component is positive."""
    direction = np.asarray(direction, dtype=float)
    direction = direction / np.linalg.norm(direction)
    return -direction if direction[np.argmax(np.abs(direction))] < 0 else direction


def _checked(markers: object, parameterisation: str) -> np.ndarray:
    """Validated markers ``(N, P, 3)`` [mm] of one trial."""
    array = check_markers(markers, min_frames=_MIN_FRAMES, min_markers=1)
    check_moves(array)
    if parameterisation not in PARAMETERISATIONS:
        raise ValueError(
            f"unknown parameterisation {parameterisation!r}; choose one of "
            f"{', '.join(PARAMETERISATIONS)}"
        )
    return array


def _given_point(point: object | None) -> np.ndarray | None:
    """The user's point ``m`` (3,) [mm], checked; ``None`` for the default."""
    if point is None:
        return None
    m = np.asarray(point, dtype=float)
    if m.shape != (3,) or not np.all(np.isfinite(m)):
        raise ValueError(f"point must be a finite (3,) array [mm], got {m!r}")
    return m


def _nm_points(arrays: list[np.ndarray]) -> list[np.ndarray | ValueError]:
    """The default point ``m`` of each validated trial: its NM sphere-fit centre (3,) [mm], or
    the ``ValueError`` of a fit without one. All trials are fitted at once; each trial's centre
    is the one it has alone (the one-trial fit goes through the same code)."""
    return [
        outcome if isinstance(outcome, ValueError) else np.asarray(outcome.center, dtype=float)
        for outcome in many("center", "NM", checked=False)(np.stack(arrays))
    ]


def _starts(parameterisation: str) -> np.ndarray:
    """The ten dodecahedron starts as search parameters, ``(10, 2)`` angles or ``(10, 3)``."""
    if parameterisation == "angles":
        return np.array([direction_to_angles(start) for start in DODECAHEDRON_STARTS])
    return np.array(DODECAHEDRON_STARTS)


def _fit_many(
    arrays: list[np.ndarray],
    points: list[np.ndarray],
    method: str,
    *,
    parameterisation: str,
    xatol: float,
    fatol: float,
    max_iter: int | None,
    max_fev: int | None,
) -> list[AxisResult]:
    """The axis of each validated trial (``arrays`` of equal shape ``(N, P, 3)``, ``points``
    ``m`` (3,)): the ten starts of every trial searched together, each on its own path."""
    costs = AxisCosts(arrays, np.stack(points))
    starts = _starts(parameterisation)
    n_starts = len(starts)
    runs = lockstep(
        costs.batch_cost(method, parameterisation, lambda owners: owners // n_starts),
        np.tile(starts, (len(arrays), 1)),
        xatol=xatol,
        fatol=fatol,
        max_iter=max_iter,
        max_fev=max_fev,
    )
    return [
        _result(
            array,
            trial,
            costs,
            runs[trial * n_starts : (trial + 1) * n_starts],
            method,
            parameterisation,
            fatol,
        )
        for trial, array in enumerate(arrays)
    ]


def _run_direction(params: object, parameterisation: str) -> np.ndarray:
    """The unit direction (3,), canonical sign, of a search's final parameters (2 angles [rad]
    or an unnormalised 3-vector)."""
    raw = angles_to_direction(*params) if parameterisation == "angles" else np.array(params)
    return canonical_sign(raw)


def _result(array, trial, costs, runs, method, parameterisation, fatol) -> AxisResult:
    """The winning start's axis of one trial, with its diagnostics and its status
    (:func:`_search_status`)."""
    winner = min(range(len(runs)), key=lambda i: runs[i][1])
    x_best, f_best, converged, iterations, evaluations = runs[winner]
    direction = _run_direction(x_best, parameterisation)
    m = costs.point[trial]
    radii = costs.radial_distances(direction, trial).mean(axis=1)
    centroid = array.reshape(-1, 3).mean(axis=0)
    foot = m + direction * float(direction @ (centroid - m))
    eigenvalues, eigenvectors = np.linalg.eigh(costs.scatter[trial])
    eigenvector = canonical_sign(eigenvectors[:, 0])
    # The search's own cost at the restart's own start, not the cost of the unit vector: the
    # restart then ends at most at it exactly, not above it by the rounding between the two.
    at_eigenvector = float(
        costs.search_cost(method, parameterisation)(
            _restart_starts([eigenvector], parameterisation), np.array([trial])
        )[0]
    )
    status = _search_status(converged, float(f_best), at_eigenvector, fatol)
    return AxisResult(
        point=m,
        direction=direction,
        radii=radii,
        converged=converged,
        iterations=iterations,
        status=status,
        method=method,
        cost=float(f_best),
        diagnostics={
            "start": winner,
            "start_costs": [float(r[1]) for r in runs],
            "start_converged": [bool(r[2]) for r in runs],
            "evaluations": evaluations,
            "total_evaluations": int(sum(r[4] for r in runs)),
            "parameterisation": parameterisation,
            "centroid_foot": foot.tolist(),
            "eigenvector": eigenvector.tolist(),
            "eigenvalues": eigenvalues.tolist(),
        },
    )


def _search_status(converged: bool, cost: float, at_eigenvector: float, fatol: float) -> str:
    """The status of a search that ended at ``cost`` [mm^2], ``converged`` or not, whose cost at
    the planar cost's eigenvector (the closed-form neighbour of every axis cost, from which the
    checked call's self-check restarts) is ``at_eigenvector``: ``"ok"`` only for a converged
    search that no such direction undercuts by more than ``fatol``. Where one does, the ten
    starts were trapped in a local minimum (on a noisy hinge, half the radial searches): the
    answer stays the method's, and the status says it is not the cost's minimum, so that a
    caller without the checks (the simulated studies) is not told ``"ok"``."""
    said = [] if converged else ["winning start stopped at the iteration/evaluation limit"]
    if at_eigenvector < cost - fatol:
        said.append(
            f"warning: not the cost's minimum: the search ended at {cost:.6g}, above the cost "
            f"at the planar cost's eigenvector, {at_eigenvector:.6g}, by more than "
            f"fatol = {fatol:g} (a restart from it, as the checked call makes, goes lower)"
        )
    return "; ".join(said) or "ok"


def _fit_trials(
    markers: object, method: str, *, point: object | None, **search
) -> list[AxisResult | ValueError]:
    """The axis of every trial of ``markers`` ``(n_trials, N, P, 3)`` [mm] (or a list of
    trials): per trial its :class:`AxisResult`, or the ``ValueError`` of a trial that cannot be
    fitted."""
    outcomes, prepared = prepare_trials(
        markers, lambda data: (_checked(data, search["parameterisation"]), _given_point(point))
    )
    if point is None and prepared:
        points = _nm_points([array for array, _ in prepared.values()])
        for trial, m in zip(list(prepared), points, strict=True):
            if isinstance(m, ValueError):
                outcomes[trial] = m
                del prepared[trial]
            else:
                prepared[trial] = (prepared[trial][0], m)
    if prepared:
        arrays, points = zip(*prepared.values(), strict=True)
        for trial, result in zip(
            prepared, _fit_many(list(arrays), list(points), method, **search), strict=True
        ):
            outcomes[trial] = result
    return outcomes


_DOC = """

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) [mm]
        The moving segment's markers in the reference segment's frame; at least 4 frames.
    point : (3,) [mm], optional
        The point ``m`` on the axis. Default: the NM sphere-fit centre (paper A), as in paper B.
    parameterisation : "angles" (default) or "vector"
        Search over azimuth/elevation, or over an unnormalised 3-vector (see the module notes).
    xatol, fatol, max_iter, max_fev
        Nelder–Mead stopping rules; defaults are ``fminsearch``'s (1e-4, 1e-4, 200 per
        parameter, 200 per parameter). A tolerance of 0 asks for the tightest the arithmetic
        allows (:func:`jointbench.numerics.simplex.nelder_mead` never stops below 10 ulp).

    Returns
    -------
    AxisResult
        ``point`` = ``m``; ``direction`` unit (3,) with its largest component positive;
        ``radii`` (n_markers,) the mean distances from the axis [mm]; ``cost`` the winning
        cost [mm^2]; ``converged``/``iterations`` of the winning start.

    Raises
    ------
    ValueError
        Bad shape, NaN/inf, fewer than 4 frames, markers that do not move, a sphere fit without
        a finite centre, or an unknown parameterisation.
    """


def _fit(markers: object, method: str, **search) -> AxisResult:
    """:func:`_fit_trials` on one trial ``(N, P, 3)`` [mm]."""
    return one_trial(_fit_trials, markers, method=method, **search)


def _entry(solve: Callable, method: str) -> Callable:
    """``solve(markers, method, **search)`` behind the estimators' keyword signature: the
    one-trial function (``solve`` = :func:`_fit`) and its many-trial form (:func:`_fit_trials`)."""

    def entry(
        markers: np.ndarray,
        *,
        point: Point | None = None,
        parameterisation: Parameterisation = "angles",
        xatol: NonNegative = XATOL,
        fatol: NonNegative = FATOL,
        max_iter: Count | None = None,
        max_fev: Count | None = None,
    ):
        return solve(
            markers,
            method,
            point=point,
            parameterisation=parameterisation,
            xatol=xatol,
            fatol=fatol,
            max_iter=max_iter,
            max_fev=max_fev,
        )

    return entry


def _self_check(result: AxisResult, markers: np.ndarray, **search) -> AxisResult:
    """The ten-start answer against one more search, started from the planar cost's closed-form
    minimum (the eigenvector of the smallest eigenvalue of ``S``, Gamage & Lasenby's axis):
    a closed-form neighbour of every axis cost, exact for a noise-free hinge, where the radial
    term's local minima can capture all ten starts (module notes). One search more than the
    fit's ten (:mod:`jointbench.estimators.selfcheck`). ``search`` are the fit's options."""
    return _self_check_many([result], markers[None], **search)[0]


def _self_check_many(
    results: list[AxisResult],
    markers: np.ndarray,
    *,
    point: object | None = None,
    parameterisation: str = "angles",
    xatol: float = XATOL,
    fatol: float = FATOL,
    max_iter: int | None = None,
    max_fev: int | None = None,
) -> list[AxisResult]:
    """:func:`_self_check` of the answers ``results`` of one method for the trials of
    ``markers`` ``(T, N, P, 3)`` [mm] (or a list of equal-shape trials), their restarts
    searched together, each on its own path (:func:`jointbench.numerics.simplex.lockstep`):
    each trial's outcome is the one it has alone."""
    del point  # each result's point is the one searched with
    method = results[0].method
    costs = AxisCosts(
        markers if isinstance(markers, np.ndarray) else list(markers),
        np.stack([np.asarray(result.point) for result in results]),
    )
    starts = _restart_starts(
        [np.asarray(result.diagnostics["eigenvector"]) for result in results], parameterisation
    )
    limits = {"xatol": xatol, "fatol": fatol, "max_iter": max_iter, "max_fev": max_fev}
    if method == "planar" and parameterisation == "angles":
        runs = _planar_restarts(costs.scatter, starts, **limits)
    else:
        runs = lockstep(costs.search_cost(method, parameterisation), starts, **limits)
    return [
        _judged(result, costs, trial, runs[trial : trial + 1], parameterisation, fatol)
        for trial, result in enumerate(results)
    ]


def _restart_starts(eigenvectors: list[np.ndarray], parameterisation: str) -> np.ndarray:
    """The self-check's restarts' starts at ``eigenvectors`` (each (3,), unit) in the search's
    ``parameterisation``: ``(k, 2)`` angles [rad] or ``(k, 3)`` vectors."""
    if parameterisation == "angles":
        return np.array([direction_to_angles(eigenvector) for eigenvector in eigenvectors])
    return np.stack(eigenvectors)


def _planar_restarts(scatter: np.ndarray, starts: np.ndarray, **limits) -> list[SimplexResult]:
    """The searches of the planar cost over angles from ``starts`` ``(T, 2)`` [rad], search
    ``t`` with the scatter ``scatter[t]`` ``(T, 3, 3)`` [mm^2], under the stopping rules
    ``limits`` of :func:`jointbench.numerics.simplex.lockstep`: what ``lockstep`` gives them
    with :meth:`AxisCosts.search_cost`, in one compiled call (:func:`_planar_angle_searches`)
    instead of a call of the cost from Python per round."""
    searches = started(starts, **limits)
    _planar_angle_searches(kernel_array(scatter), tuple(searches), np.empty(len(searches.points)))
    return searches.results()


@kernel
def _planar_angle_searches(scatter: np.ndarray, searches: tuple, costs: np.ndarray) -> None:
    """Runs the ``searches`` of :func:`jointbench.numerics.simplex.started` over azimuth and
    elevation [rad] to their end, search ``r`` on the planar cost ``n' S n`` of
    ``S = scatter[r]`` ``(R, 3, 3)`` [mm^2]; ``costs`` ``(R (n + 1),)`` is scratch. A compiled
    kernel: each direction is :func:`angles_to_directions`'s (:func:`direction_into`) and its
    cost :func:`_planar_costs`'s, by the same operations in the same order."""
    points, owners = searches[-2], searches[-1]
    direction = np.empty(3)
    while True:
        # Each round takes the costs of the points asked for last (none at the start).
        count = advance(*searches, costs)
        if count == 0:
            return
        for k in range(count):
            direction_into(points[k, 0], points[k, 1], direction)
            s = scatter[owners[k]]
            total = 0.0
            for i in range(3):
                for j in range(3):
                    total += direction[i] * s[i, j] * direction[j]
            costs[k] = total


@kernel
def direction_into(azimuth: float, elevation: float, direction: np.ndarray) -> None:
    """:func:`angles_to_direction` of ``azimuth`` and ``elevation`` [rad] written into
    ``direction`` (3,), inside a compiled kernel: the sines and cosines are the C library's,
    which NumPy's are where it has no vectorised ones of its own
    (``tests/test_axis_planar_cost.py`` holds them to NumPy's)."""
    c = math.cos(elevation)
    direction[0] = c * math.cos(azimuth)
    direction[1] = c * math.sin(azimuth)
    direction[2] = math.sin(elevation)


def _judged(result, costs, trial, run, parameterisation, fatol) -> AxisResult:
    """``result`` of ``trial`` judged against the ``run`` of its restart (:func:`_self_check`),
    then against the other of the two minima where they lie far apart
    (:func:`_ambiguity_checked`)."""
    restart_cost = float(run[0][1])
    array = costs.trial_markers(trial)
    if not restart_cost < result.cost - fatol:
        judged = selfcheck.held(
            result,
            f"a restart from the planar-cost eigenvector reached {restart_cost:.6g}, not below "
            f"the answer's {result.cost:.6g} by more than fatol = {fatol:g}",
        )
        other = (_run_direction(run[0][0], parameterisation), restart_cost)
    else:
        better = _result(array, trial, costs, run, result.method, parameterisation, fatol)
        angle = angle_between_lines_deg(better.direction, result.direction)
        judged = selfcheck.restarted(
            result,
            better,
            "the planar-cost eigenvector",
            f"{angle:.3g} deg from the ten starts' axis, which is replaced",
        )
        other = (np.asarray(result.direction), result.cost)
    return _ambiguity_checked(judged, array, *other)


def _ambiguity_checked(
    result: AxisResult, markers: np.ndarray, direction: np.ndarray, cost: float
) -> AxisResult:
    """``result`` for ``markers`` ``(N, P, 3)`` [mm] judged against another minimum of its
    cost, at ``direction`` (3,) with ``cost`` [mm^2]: unchanged within
    :data:`jointbench.estimators.precision.AMBIGUOUS_APART_DEG` of the answer (the same
    minimum), else with the other minimum in its diagnostics and, where the data cannot tell
    the two fits apart (:func:`jointbench.estimators.precision.ambiguity`), a warning."""
    if _surely_within(direction, result.direction, _APART_COSINE):
        return result
    angle = angle_between_lines_deg(direction, result.direction)
    if not angle > precision.AMBIGUOUS_APART_DEG:
        return result
    squares = _sample_squares(
        np.asarray(result.point), np.stack([result.direction, direction]), markers, result.method
    )
    other = {"direction": np.asarray(direction).tolist(), "cost": cost, "angle_deg": float(angle)}
    return precision.annotate_ambiguity(
        result, other, *precision.ambiguity(*squares), f"the {result.method} cost"
    )


# Lines whose cosine is at least this are within AMBIGUOUS_APART_DEG of each other whatever
# the rounding of either (half a degree inside it, a margin of 4e-3 in the cosine).
_APART_COSINE = math.cos(math.radians(precision.AMBIGUOUS_APART_DEG - 0.5))


def _surely_within(a: np.ndarray, b: np.ndarray, cosine: float) -> bool:
    """Whether the lines along ``a`` and ``b`` (3,), of any non-zero length, are at an angle
    whose cosine is at least ``cosine``: the usual answer of the self-check's comparison of its
    two minima, told in a few float operations where
    :func:`jointbench.geometry.angle_between_lines_deg` costs a tenth of a millisecond; False
    where that is not certain (the angle is then measured)."""
    a0, a1, a2 = np.asarray(a, dtype=float).tolist()
    b0, b1, b2 = np.asarray(b, dtype=float).tolist()
    dot = a0 * b0 + a1 * b1 + a2 * b2
    squares = (a0 * a0 + a1 * a1 + a2 * a2) * (b0 * b0 + b1 * b1 + b2 * b2)
    # NaN, a zero vector or an overflow fails the comparisons: not certain.
    return 0.0 < squares < math.inf and dot * dot >= cosine * cosine * squares


def _sample_squares(
    point: np.ndarray, directions: np.ndarray, markers: np.ndarray, method: str
) -> np.ndarray:
    """Each distinct marker sample's squared residuals under ``method``'s cost (summed where
    the cost has two, the combined one), for each axis through ``point`` (3,) [mm] along
    ``directions`` ``(k, 3)``: ``(k, P, N_d)`` [mm^2] for ``markers`` ``(N, P, 3)`` [mm].
    Frames repeated exactly carry no new noise
    (:func:`jointbench.estimators.precision.distinct_frames`)."""
    markers = precision.distinct_frames(markers)
    costs = AxisCosts(markers, point)
    squares = np.zeros((len(directions), *costs.trial_markers(0).shape[1::-1]))
    if method != "planar":
        distances = costs.radial_distances(directions)
        squares += (distances - distances.mean(axis=-1, keepdims=True)) ** 2
    if method != "radial":
        offsets = markers - markers.mean(axis=0)
        squares += np.einsum("npi,ki->kpn", offsets, directions) ** 2
    return squares


# The residuals each cost sums per marker sample (:func:`_direction_sd_deg`).
_RESIDUAL_SETS = {"planar": 1, "radial": 1, "combined": 2}


def _planar_hessian(
    scatter: np.ndarray, direction: np.ndarray, basis: np.ndarray, cost: float | None = None
) -> np.ndarray:
    """The Hessian ``(2, 2)`` [mm^2/rad^2] of ``f_p = n' S n`` in the tangent angles ``a`` of
    ``n(a) = (n + E a) / |n + E a|`` at ``a = 0``: ``2 (E' S E - (n' S n) I)``, ``S`` the
    scatter ``(3, 3)`` [mm^2], ``E`` the basis ``(3, 2)``; ``cost``, where the caller has it,
    is ``n' S n`` [mm^2] at the unit ``direction`` ``n`` (3,). Exact at any ``n``; at the
    minimum it is the curvature left above the noise's own share of ``S``, which a
    Gauss–Newton ``2 E' S E`` would count as signal."""
    if cost is None:
        cost = float(direction @ scatter @ direction)
    return 2.0 * (basis.T @ scatter @ basis - cost * _IDENTITY_2)


# The identity of the tangent angles (_planar_hessian), made once: read, never written.
_IDENTITY_2 = np.eye(2)
_IDENTITY_2.setflags(write=False)


def _radial_derivatives(
    markers: np.ndarray, foot: np.ndarray, direction: np.ndarray, basis: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float, float, np.ndarray, np.ndarray]:
    """The radial cost (radii profiled out) at the axis through ``foot`` (3,) [mm] along
    ``direction`` (3,), for ``markers`` ``(N, P, 3)`` [mm], with its gradient ``(4,)`` and
    exact Hessian ``(4, 4)`` in the tangent angles ``a`` [rad] of :func:`_planar_hessian` and
    the axis's shift ``b`` [mm] along ``basis`` ``E`` ``(3, 2)``, its residuals' fourth
    powers summed, the Hessian's Gauss–Newton part ``2 sum grad(rho) grad(rho)'`` ``(4, 4)``,
    and the expected value of the rest, the residuals' own term ``-2 sum rho d2d``, under
    isotropic noise of unit variance per coordinate ``(4, 4)`` [per mm^2]:
    ``(gradient, hessian, cost, fourths, gauss_newton, unit_noise_term)``.

    A sample's offset ``w = v - m`` has ``c = n . w`` along the axis and ``x = E' w`` across it,
    its distance being ``d = |x|``. At ``a = b = 0``: ``dd/da = -c x / d``,
    ``dd/db = -x / d``; ``d2d/da2 = (c^2 I - x x') / d - c^2 x x' / d^3``,
    ``d2d/dadb = c (I / d - x x' / d^3)``, ``d2d/db2 = I / d - x x' / d^3``. With the radii
    profiled, a residual is ``rho = d - mean_k d`` of its marker, the gradient of ``sum rho^2``
    is ``2 sum rho grad(d)`` and its Hessian ``2 sum grad(rho) grad(rho)' + 2 sum rho d2d``
    (the radii's own derivatives sum to zero against ``rho``). A marker on the axis
    (``d = 0``), where the cost has no derivative, gives a Hessian that is not finite.

    The noise's term: a sample's noise ``e`` (variance ``s^2`` per coordinate) moves ``rho`` by
    ``(1 - 1/N) u . e`` (``u = x / d``; along the axis and around it, not at all) and ``d2d``
    by that radial step times ``d(d2d)/dd`` at fixed ``u`` and ``c``: ``-(c^2 (I - u u') / d^2
    + u u')``, ``-c (I - u u') / d^2``, ``-(I - u u') / d^2`` in the three blocks. So
    ``E[-2 sum rho d2d] = 2 s^2 (1 - 1/N) sum (blocks of (I - u u') / d^2 times c^2, c, 1,
    plus u u' in the angle-angle block)`` to second order in the noise (read at the answer in
    place of the noise-free axis): ``tests/test_axis_sd.py`` holds it to the mean of
    ``G - H`` over noise draws.

    Summed in one compiled pass over the samples (:func:`_radial_sums`): the paper's three
    costs all state the point's precision through these derivatives, and as NumPy arrays of
    every sample they cost a long trial's planar check ten times its own statement."""
    gradient, hessian = np.empty(4), np.empty((4, 4))
    gauss_newton, unit_noise_term = np.empty((4, 4)), np.empty((4, 4))
    cost, fourths = _radial_sums(
        kernel_array(markers),
        kernel_array(foot),
        kernel_array(direction),
        kernel_array(basis),
        gradient,
        hessian,
        gauss_newton,
        unit_noise_term,
    )
    return gradient, hessian, cost, fourths, gauss_newton, unit_noise_term


@kernel
def _radial_sums(
    markers: np.ndarray,
    foot: np.ndarray,
    direction: np.ndarray,
    basis: np.ndarray,
    gradient: np.ndarray,
    hessian: np.ndarray,
    gauss_newton: np.ndarray,
    unit_noise_term: np.ndarray,
) -> tuple[float, float]:
    """:func:`_radial_derivatives` of ``markers`` ``(N, P, 3)`` [mm]: the gradient into
    ``gradient`` ``(4,)``, the Hessian into ``hessian`` ``(4, 4)``, its Gauss–Newton part into
    ``gauss_newton`` and the residuals' term's expected value under unit noise into
    ``unit_noise_term`` (both ``(4, 4)``); returns the cost [mm^2] and its residuals' fourth
    powers [mm^4]. A compiled kernel: per marker, a first pass over
    its frames for the means of its distance and of the distance's gradient, which the radii
    profiled out subtract (two passes: on a short arc the gradient barely changes, and its
    centred products would cancel in one), and a second for the sums; the second derivatives'
    ``(2, 2)`` blocks are summed as the scalar sums they are made of. Every sum is a scalar of
    its own, which the compiler keeps in a register: in arrays each term was a load and a
    store, a sixth of the pass's time on a long trial."""
    n_frames, n_markers, _ = markers.shape
    cost, fourths = 0.0, 0.0
    # The gradient's sums, sum rho grad(d), and the centred products' upper triangle.
    g0 = g1 = g2 = g3 = 0.0
    h00 = h01 = h02 = h03 = h11 = h12 = h13 = h22 = h23 = h33 = 0.0
    # Per block weight (c^2, c, 1): sum w, sum w u0 u0, sum w u0 u1, sum w u1 u1 (w = rho / d,
    # _weighted); and sum rho d u u' (u0 u0, u0 u1, u1 u1).
    aa = ab = bb = (0.0, 0.0, 0.0, 0.0)
    outer0 = outer1 = outer2 = 0.0
    # The noise's term (_radial_derivatives): sum u u', and the same sums with w = 1 / d^2.
    radial0 = radial1 = radial2 = 0.0
    noise_aa = noise_ab = noise_bb = (0.0, 0.0, 0.0, 0.0)
    # A marker's samples in the axis's coordinates (c, u0, u1, d), kept from the first pass.
    coordinates = np.empty((n_frames, 4))
    for p in range(n_markers):
        mean_distance = 0.0
        mean0 = mean1 = mean2 = mean3 = 0.0
        for k in range(n_frames):
            c, x0, x1, d = _axis_coordinates(markers[k, p], foot, direction, basis)
            u0, u1 = x0 / d, x1 / d
            coordinates[k, 0], coordinates[k, 1], coordinates[k, 2] = c, u0, u1
            coordinates[k, 3] = d
            mean_distance += d
            mean0 -= c * u0
            mean1 -= c * u1
            mean2 -= u0
            mean3 -= u1
        mean_distance /= n_frames
        mean0, mean1, mean2, mean3 = (
            mean0 / n_frames,
            mean1 / n_frames,
            mean2 / n_frames,
            mean3 / n_frames,
        )
        for k in range(n_frames):
            c, u0, u1, d = (
                coordinates[k, 0],
                coordinates[k, 1],
                coordinates[k, 2],
                coordinates[k, 3],
            )
            s0, s1, s2, s3 = -c * u0, -c * u1, -u0, -u1
            residual = d - mean_distance
            squared = residual * residual
            cost += squared
            fourths += squared * squared
            g0, g1 = g0 + residual * s0, g1 + residual * s1
            g2, g3 = g2 + residual * s2, g3 + residual * s3
            o0, o1, o2, o3 = s0 - mean0, s1 - mean1, s2 - mean2, s3 - mean3
            h00 += o0 * o0
            h01 += o0 * o1
            h02 += o0 * o2
            h03 += o0 * o3
            h11 += o1 * o1
            h12 += o1 * o2
            h13 += o1 * o3
            h22 += o2 * o2
            h23 += o2 * o3
            h33 += o3 * o3
            weight = residual / d
            u00, u01, u11 = u0 * u0, u0 * u1, u1 * u1
            aa = _weighted(aa, weight * (c * c), u00, u01, u11)
            ab = _weighted(ab, weight * c, u00, u01, u11)
            bb = _weighted(bb, weight, u00, u01, u11)
            rd = residual * d
            outer0 += rd * u00
            outer1 += rd * u01
            outer2 += rd * u11
            radial0, radial1, radial2 = radial0 + u00, radial1 + u01, radial2 + u11
            inverse = 1.0 / (d * d)
            noise_aa = _weighted(noise_aa, inverse * (c * c), u00, u01, u11)
            noise_ab = _weighted(noise_ab, inverse * c, u00, u01, u11)
            noise_bb = _weighted(noise_bb, inverse, u00, u01, u11)
    gradient[0], gradient[1], gradient[2], gradient[3] = 2.0 * g0, 2.0 * g1, 2.0 * g2, 2.0 * g3
    centred = (
        (h00, h01, h02, h03),
        (0.0, h11, h12, h13),
        (0.0, 0.0, h22, h23),
        (0.0, 0.0, 0.0, h33),
    )
    for i in range(4):
        for j in range(i, 4):
            hessian[i, j] = hessian[j, i] = 2.0 * centred[i][j]
            gauss_newton[i, j] = gauss_newton[j, i] = 2.0 * centred[i][j]
    # The noise's term: 2 (1 - 1/N) times the blocks sum (I - u u') / d^2 times c^2, c and 1,
    # plus sum u u' in the angle-angle block.
    factor = 2.0 * (1.0 - 1.0 / n_frames)
    unit_noise_term[:, :] = 0.0
    _add_tangential_blocks(unit_noise_term, (noise_aa, noise_ab, noise_bb), factor)
    unit_noise_term[0, 0] += factor * radial0
    unit_noise_term[0, 1] += factor * radial1
    unit_noise_term[1, 0] += factor * radial1
    unit_noise_term[1, 1] += factor * radial2
    # 2 sum rho d2d: the blocks sum w (I - u u') times c^2 (angle-angle), c (angle-shift) and
    # 1 (shift-shift), less sum rho d u u' in the angle-angle block.
    _add_tangential_blocks(hessian, (aa, ab, bb), 2.0)
    hessian[0, 0] -= 2.0 * outer0
    hessian[0, 1] -= 2.0 * outer1
    hessian[1, 0] -= 2.0 * outer1
    hessian[1, 1] -= 2.0 * outer2
    return cost, fourths


@kernel
def _weighted(
    sums: tuple[float, float, float, float], weight: float, u00: float, u01: float, u11: float
) -> tuple[float, float, float, float]:
    """``sums`` of a weight ``w`` and of ``w`` times ``u0 u0``, ``u0 u1``, ``u1 u1`` with one
    sample's ``weight`` and products added (:func:`_radial_sums`). A compiled kernel."""
    return (
        sums[0] + weight,
        sums[1] + weight * u00,
        sums[2] + weight * u01,
        sums[3] + weight * u11,
    )


@kernel
def _add_tangential_blocks(matrix: np.ndarray, sums: tuple, scale: float) -> None:
    """Add to ``matrix`` ``(4, 4)`` ``scale`` times the blocks ``sum w (I - u u')`` of the
    angle-angle, angle-shift (and its transpose) and shift-shift parts, from each block's
    :func:`_weighted` ``sums``. A compiled kernel."""
    for b, (row, column) in enumerate(((0, 0), (0, 2), (2, 2))):
        t = sums[b]
        block = ((t[0] - t[1], -t[2]), (-t[2], t[0] - t[3]))
        for i in range(2):
            for j in range(2):
                matrix[row + i, column + j] += scale * block[i][j]
                if row != column:
                    matrix[column + j, row + i] += scale * block[i][j]


@kernel
def _axis_coordinates(
    point: np.ndarray, foot: np.ndarray, direction: np.ndarray, basis: np.ndarray
) -> tuple[float, float, float, float]:
    """A ``point`` (3,) [mm] in the coordinates of the axis through ``foot`` (3,) along
    ``direction`` (3,): ``(c, x0, x1, d)``, its height ``c`` along the axis, its offset
    ``x = E' (point - foot)`` across it in the ``basis`` ``E`` ``(3, 2)`` and ``d = |x|``
    [mm]. A compiled kernel."""
    w0, w1, w2 = point[0] - foot[0], point[1] - foot[1], point[2] - foot[2]
    c = w0 * direction[0] + w1 * direction[1] + w2 * direction[2]
    x0 = w0 * basis[0, 0] + w1 * basis[1, 0] + w2 * basis[2, 0]
    x1 = w0 * basis[0, 1] + w1 * basis[1, 1] + w2 * basis[2, 1]
    return c, x0, x1, math.sqrt(x0 * x0 + x1 * x1)


def _direction_sd_deg(markers: np.ndarray, point: np.ndarray, direction: np.ndarray, method: str):
    """The SD [deg] of :func:`_direction_precision`."""
    return _direction_precision(markers, point, direction, method)[0]


def _planar_gap(planar_hessian: np.ndarray) -> float:
    """The planar eigen-problem's gap [mm^2] above the answer ``n``: the smallest eigenvalue of
    ``E' S E - (n' S n) I``, half the ``planar_hessian`` ``(2, 2)`` [mm^2/rad^2] that
    :func:`_planar_hessian` gives at ``n``; at the minimum, the smaller of ``S``'s two other
    eigenvalues less the answer's."""
    return precision.smaller_eigenvalue(0.5 * planar_hessian)


def _planar_terms(
    markers: np.ndarray, direction: np.ndarray, basis: np.ndarray, fourths: bool = True
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The planar cost ``n' S n`` [mm^2] at the unit ``direction`` ``n`` (3,) on the distinct
    frames ``markers`` ``(N_d, P, 3)`` [mm], with its gradient ``(2,)`` and Hessian ``(2, 2)``
    in the tangent angles of ``basis`` ``(3, 2)`` (:func:`_planar_hessian`) and its residuals'
    fourth powers summed [mm^4], NaN unless ``fourths`` asks for them (a pass over every
    sample): ``(gradient, hessian, cost, fourths)``. ``S`` does not depend on the axis's
    point: the planar cost needs no foot, whose centroid of every sample costs more than ``S``
    itself on a long trial."""
    scatter = trial_scatter(markers)
    cost = float(direction @ scatter @ direction)
    gradient = 2.0 * basis.T @ scatter @ direction
    summed = (
        _height_fourths(kernel_array(markers), kernel_array(direction)) if fourths else math.nan
    )
    return gradient, _planar_hessian(scatter, direction, basis, cost), cost, summed


def _cost_at(
    markers: np.ndarray, point: np.ndarray, direction: np.ndarray, method: str, fourths: bool = True
) -> precision.CostAt:
    """``method``'s cost at the axis through ``point`` (3,) [mm] along ``direction`` (3,) on the
    distinct frames ``markers`` ``(N_d, P, 3)`` [mm], with its analytic gradient and Hessian
    (:func:`_direction_precision`), the Hessian's Gauss–Newton part and the residuals' term's
    expected value under unit noise (:func:`jointbench.estimators.precision.noise_share`); its
    residuals' fourth powers NaN unless ``fourths`` asks for them (the point's covariance does
    not read them, and the planar residuals' take a pass over every sample:
    :func:`_planar_terms`)."""
    n_frames, n_markers = markers.shape[:2]
    basis = precision.tangent_basis(direction)
    n_params = 2 if method == "planar" else 4
    gradient, hessian = np.zeros(n_params), np.zeros((n_params, n_params))
    gauss_newton, unit_noise_term = np.zeros((n_params, n_params)), np.zeros((n_params, n_params))
    cost, summed = 0.0, 0.0
    if method != "radial":
        gradient[:2], hessian[:2, :2], cost, summed = _planar_terms(
            markers, direction, basis, fourths
        )
        # The planar residuals n . u have second derivative -(n . u) I in the tangent angles
        # (_planar_hessian): their term is 2 (n' S n) I, whose expected value under noise of
        # unit variance is 2 I per residual less the centroids taken out, P (N - 1).
        gauss_newton[:2, :2] = hessian[:2, :2] + 2.0 * cost * _IDENTITY_2
        unit_noise_term[:2, :2] = 2.0 * n_markers * (n_frames - 1) * _IDENTITY_2
    if method != "planar":
        foot = point + direction * float(direction @ (_centroid(markers) - point))
        radial = _radial_derivatives(markers, foot, direction, basis)
        gradient, hessian = gradient + radial[0], hessian + radial[1]
        cost, summed = cost + radial[2], summed + radial[3]
        gauss_newton, unit_noise_term = gauss_newton + radial[4], unit_noise_term + radial[5]
    n_residuals = _RESIDUAL_SETS[method] * n_markers * n_frames
    dof = _RESIDUAL_SETS[method] * n_markers * (n_frames - 1) - n_params
    return precision.cost_at(
        gradient, hessian, cost, summed, n_residuals, dof, gauss_newton, unit_noise_term
    )


def _direction_precision(
    markers: np.ndarray, point: np.ndarray, direction: np.ndarray, method: str
) -> tuple[float, tuple[float, float] | None]:
    """The SD [deg] of the axis ``direction`` (3,) through ``point`` (3,) [mm] implied by
    ``method``'s cost on ``markers`` ``(N, P, 3)`` [mm] (:mod:`jointbench.estimators.precision`).

    Residuals, on the distinct frames ``N_d``: the planar cost's ``n . u`` of every sample
    (``P N_d``, less the ``P`` centroids the offsets ``u`` are taken from), the radial cost's
    distance less its marker's radius (``P N_d``, less the ``P`` radii profiled out), the
    combined cost both. Parameters: the direction (2) and, for the radial and combined costs,
    the axis's position normal to it (2): the search holds ``m`` at the NM centre, but that is
    fitted to the same markers and is no better determined off the axis than the cylinders'
    axis is, so the direction's SD must allow for it (with ``m`` held, one 2 degree arc's
    radial minimum looks sharp to 0.14 degrees and lies 40 degrees off). The axis is
    taken through the foot nearest the markers' centroid (where ``m`` lies along the axis does
    not change the costs; about a far ``m`` a tilt would also shift the axis at the markers).

    The Hessians are analytic (:func:`_planar_hessian`, :func:`_radial_derivatives`): a central
    difference needs a step well inside the arc (on a 2 degree arc the cost departs from its
    quadratic by several percent at 1e-3 rad) while the tilt and shift of the axis that the
    arc leaves nearly free curve the cost 1e-5 as much as the others, which rounding hides at
    any step that small.

    Also, for the planar cost, whose answer is an eigenvector of ``S``, the noise's share of
    its eigen-problem and its gap ``(n' S n, gap)`` [mm^2] (:func:`_planar_gap`), which tell
    whether the first-order SD holds (:func:`jointbench.estimators.precision.annotate_validity`);
    ``None`` for the others, whose radial term curves the cost on its own.
    """
    at = _cost_at(precision.distinct_frames(markers), point, direction, method)
    return _precision_of(at, method)


def _precision_of(at: precision.CostAt, method: str) -> tuple[float, tuple[float, float] | None]:
    """:func:`_direction_precision` of ``method``'s cost ``at`` an axis."""
    sd = precision.direction_sd_deg(at)
    if method != "planar":
        return sd, None
    return sd, (at.cost, _planar_gap(at.hessian))


def _annotated(result: AxisResult, markers: np.ndarray, verdict: Support) -> AxisResult:
    """``result`` for ``markers`` ``(N, P, 3)`` [mm] with its direction's SD
    (:func:`_direction_precision`), where the first-order SD does not hold the planar
    eigen-problem's warning, the segment's travel along the axis, which every one of these
    costs' models excludes (:func:`jointbench.estimators.precision.annotate_travel`), and its
    cost's misfit against the support ``verdict``'s rigid-body noise
    (:func:`jointbench.estimators.precision.misfit`), and its point's precision across the
    axis (:func:`_point_covariance`)."""
    markers = precision.distinct_frames(markers)
    at = _cost_at(markers, np.asarray(result.point), np.asarray(result.direction), result.method)
    sd, eigen = _precision_of(at, result.method)
    cost_name = f"the {result.method} cost"
    annotated = _first_order_annotated(precision.annotate(result, sd, cost_name), markers, verdict)
    if result.method == "radial":
        annotated = _checked_against_planar(annotated, markers)
    elif eigen is not None:
        annotated = precision.annotate_validity(annotated, *eigen, "the planar cost's scatter")
    annotated = precision.annotate_travel(annotated, verdict.motion_axis, cost_name)
    annotated = _misfit_annotated(annotated, at, markers.shape[:2], verdict)
    return precision.annotate_point(annotated, *_point_covariance(result, markers, at, verdict))


def _point_covariance(
    result: AxisResult, markers: np.ndarray, at: precision.CostAt, verdict: Support
) -> tuple[np.ndarray, float]:
    """The covariance ``(3, 3)`` [mm^2] of ``result``'s point ``m`` across the axis, for the
    distinct frames ``markers`` ``(N_d, P, 3)`` [mm] (module notes: which point, and why the
    circles' cost states it): :func:`jointbench.estimators.precision.point_covariance` of the
    combined cost at the combined answer's own line (``at``, where its direction's SD was
    read), else at the line through ``m`` along the planar eigenvector the result carries; on
    the markers that read the rotation to first order where the support ``verdict``'s levers
    leave some out but not all, as the direction's SD is read
    (:func:`_first_order_annotated`). With it, for the combined answer, the stated noise's
    share of that cost's curvature (:func:`jointbench.estimators.precision.noise_share`, the
    verdict's rigid-body noise): its line is that cost's own minimum, which no other check
    holds to the noise's share (module notes); NaN for the others, whose lines are the planar
    eigenvector's, held to its eigen-problem's share (the planar answer's own check, and the
    radial answer's comparison with it)."""
    point = np.asarray(result.point)
    first_order = precision.first_order_markers(verdict.motion_axis)
    if first_order is not None and first_order.any() and not first_order.all():
        markers = markers[:, first_order]
    elif result.method == "combined":
        covariance = _point_covariance_at(at, point, np.asarray(result.direction), markers)
        return covariance, precision.noise_share(at, _noise_variance(verdict))
    direction = np.asarray(
        result.direction if result.method == "combined" else result.diagnostics["eigenvector"]
    )
    at = _cost_at(markers, point, direction, "combined", fourths=False)
    covariance = _point_covariance_at(at, point, direction, markers)
    if result.method != "combined":
        return covariance, math.nan
    return covariance, precision.noise_share(at, _noise_variance(verdict))


def _noise_variance(verdict: Support) -> float:
    """The marker noise's variance per coordinate [mm^2] the support ``verdict`` states, from
    its rigid-body residual; NaN where it did not assess the data."""
    if not verdict.diagnostics.get("assessed", False):
        return math.nan
    return verdict.diagnostics["rigid_residual_mm"] ** 2 / 3.0


def _point_covariance_at(
    at: precision.CostAt, point: np.ndarray, direction: np.ndarray, markers: np.ndarray
) -> np.ndarray:
    """:func:`jointbench.estimators.precision.point_covariance` of ``point`` (3,) [mm] on the
    line along ``direction`` (3,) whose combined cost on ``markers`` ``(N_d, P, 3)`` [mm] is
    ``at``: its height is read from the markers' centroid, the cost's foot."""
    height = float(direction @ (point - _centroid(markers)))
    return precision.point_covariance(at, direction, height)


def _centroid(markers: np.ndarray) -> np.ndarray:
    """The centroid (3,) [mm] of every sample of ``markers`` ``(N, P, 3)`` [mm]: the foot of an
    axis cost's tilt and shift (:func:`_cost_at`), from which the point's height is read
    (:func:`_point_covariance_at`); read-only, computed once per array in a checked call
    (:func:`jointbench.numerics.reuse.remembered`)."""
    return remembered("sample centroid", markers, _centroid_of)


def _centroid_of(markers: np.ndarray) -> np.ndarray:
    """:func:`_sample_centroid` of ``markers`` ``(N, P, 3)`` [mm], read-only (3,) [mm]."""
    centroid = _sample_centroid(kernel_array(markers))
    centroid.setflags(write=False)
    return centroid


@kernel
def _sample_centroid(markers: np.ndarray) -> np.ndarray:
    """:func:`_centroid` in a compiled kernel: NumPy's mean over the samples' axis of a
    ``(N P, 3)`` view costs a long trial's planar check several times the sum."""
    total = np.zeros(3)
    for k in range(markers.shape[0]):
        for p in range(markers.shape[1]):
            for i in range(3):
                total[i] += markers[k, p, i]
    return total / (markers.shape[0] * markers.shape[1])


def _first_order_annotated(result: AxisResult, markers: np.ndarray, verdict: Support) -> AxisResult:
    """The radial or combined ``result`` for ``markers`` ``(N_d, P, 3)`` [mm] with the SD of
    its direction that its cost on the markers that read the rotation to first order implies
    (:func:`jointbench.estimators.precision.annotate_first_order`), where the support
    ``verdict``'s levers leave some out but not all (where none reads it, the comparison with
    the motion's axis says so: :func:`jointbench.estimators.precision.annotate_motion_axis`).
    The planar answer is held to its own check of the noise's share of its scatter
    (:func:`jointbench.estimators.precision.annotate_validity`), which the others lack."""
    first_order = precision.first_order_markers(verdict.motion_axis)
    if result.method == "planar" or first_order is None:
        return result
    if first_order.all() or not first_order.any():
        return result
    point, direction = np.asarray(result.point), np.asarray(result.direction)
    if not (np.isfinite(point).all() and np.isfinite(direction).all()):
        return result
    at = _cost_at(markers[:, first_order], point, direction, result.method)
    return precision.annotate_first_order(result, precision.direction_sd_deg(at), first_order)


def _misfit_annotated(
    result: AxisResult, at: precision.CostAt, shape: tuple[int, int], verdict: Support
) -> AxisResult:
    """``result`` with its cost's misfit ``at`` its axis against the rigid-body noise of the
    support ``verdict`` on markers of ``shape`` ``(N_d, P)``
    (:func:`jointbench.estimators.precision.misfit`), which the comparison with the motion's
    axis reads (:func:`jointbench.estimators.precision.annotate_motion_axis`)."""
    if not verdict.diagnostics.get("assessed", False):
        why = "the support verdict did not assess the data (no rigid-body residual)"
        return precision.annotate_misfit(result, None, why)
    noise = _noise_variance(verdict)
    n_frames, n_markers = shape
    found = precision.misfit(at, noise, precision.rigid_dof(n_markers, n_frames))
    if found is None:
        why = "the cost does not rise in every direction from the answer, or has no residuals"
        return precision.annotate_misfit(result, None, why)
    return precision.annotate_misfit(result, found)


def _checked_against_planar(result: AxisResult, markers: np.ndarray) -> AxisResult:
    """The radial ``result`` for ``markers`` ``(N, P, 3)`` [mm] compared with the planar
    cost's closed-form answer, the eigenvector it carries, and warned about where the two are
    further apart than their SDs allow
    (:func:`jointbench.estimators.precision.annotate_agreement`)."""
    planar = np.asarray(result.diagnostics["eigenvector"])
    planar_sd = _direction_sd_deg(markers, np.asarray(result.point), planar, "planar")
    return precision.annotate_agreement(
        result, planar, planar_sd, "the radial cost", "the planar cost's eigenvector"
    )


def _precision_many(
    results: list[AxisResult], markers: np.ndarray, *, verdicts: list[Support]
) -> list[AxisResult]:
    """Each of ``results`` (one method's answers for the trials of ``markers``
    ``(T, N, P, 3)`` [mm] or a list of trials) with its direction's SD, above
    :data:`jointbench.estimators.precision.MAX_AXIS_SD_DEG` a warning, for the planar
    cost the warning where the SD does not hold, and its cost's misfit against the rigid-body
    noise of the trial's support verdict in ``verdicts`` (:func:`_annotated`)."""
    return [
        _annotated(result, np.asarray(array, dtype=float), verdict)
        for result, array, verdict in zip(results, markers, verdicts, strict=True)
    ]


def _make(method: str, summary: str) -> Callable[..., AxisResult]:
    fit = _entry(_fit, method)
    fit.__name__ = fit.__qualname__ = f"fit_{method}"
    fit.__doc__ = summary + _DOC
    fit.self_check = _self_check
    fit.self_check_many = _self_check_many
    fit.precision_many = _precision_many
    return fit


def _many(method: str) -> Callable[..., list]:
    return isolated(_entry(_fit_trials, method), min_frames=_MIN_FRAMES)


_CLAIMS = {"recovery": 1e-4, "invariances": 1e-4, "min_frames": _MIN_FRAMES}
fit_planar = register(
    "axis", "planar", **_CLAIMS, many=_many("planar"), color="#6a3d9a", marker="s"
)(_make("planar", "Normal of the best-fitting parallel planes, paper B eq. 8, by search."))
# On a pure hinge the default point (the NM centre) is undetermined along the axis and can
# land where all ten radial searches are trapped (module notes); the recovery claim holds for
# the checked call, whose self-check restarts from the planar eigenvector (_self_check).
fit_radial = register(
    "axis", "radial", **_CLAIMS, many=_many("radial"), color="#b2182b", marker="^"
)(_make("radial", "Axis of the best-fitting coaxial cylinders through m, paper B eqs. 10–11."))
fit_combined = register(
    "axis", "combined", **_CLAIMS, many=_many("combined"), color="#17becf", marker="o"
)(_make("combined", "Axis of the best-fitting coaxial circles, paper B eq. 12 (planar + radial)."))
