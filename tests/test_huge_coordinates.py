"""Coordinates too large for float64's arithmetic are refused where every public entry reads them.

A finite coordinate of 1e200 mm squares past float64's range: the checks' own sums overflowed
into NaN and escaped as NumPy's ``LinAlgError``. Every entry that takes marker arrays (the
checked and bare one-trial calls and the many-trial calls of every method of every kind, the
input checks, the support verdict, the artefact screen, the public fits, a recording's fit)
meets such a coordinate, a whole marker or frame of them, data offset by 1e200, subnormal data
and huge values mixed with a NaN, with a ``ValueError`` naming the array, and the marker and
frame of the first sample at fault (the screen, which reads NaN as a gap: the first huge one);
never another exception. :func:`jointbench.numerics.magnitudes.largest_coordinate` states the
bound. Subnormal data are a cluster at one point where no unit is read (the sample checks, the
screen) and refused where one is.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from rigs import two_segments

import jointbench
from jointbench import screening
from jointbench.estimators import registry, support, validation
from jointbench.numerics.magnitudes import first_beyond, largest_coordinate

N_FRAMES = 40


def _one_segment(kind: str) -> np.ndarray:
    """The distal markers of a ball joint (centre) or a hinge (axis), in the proximal frame."""
    rng = np.random.default_rng(3)
    _, distal = two_segments(
        N_FRAMES, relative="ball" if kind == "center" else "hinge", proximal_moves=False
    )
    return distal + rng.normal(scale=0.3, size=distal.shape)


def _two_segments() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(4)
    proximal, distal = two_segments(N_FRAMES)
    return (
        proximal + rng.normal(scale=0.3, size=proximal.shape),
        distal + rng.normal(scale=0.3, size=distal.shape),
    )


def _set(value: float, *where):
    def spoil(markers: np.ndarray) -> tuple[np.ndarray, tuple[int, int] | None]:
        spoilt = markers.copy()
        spoilt[where] = value
        frame, marker = np.argwhere((spoilt != markers).any(axis=-1))[0]
        return spoilt, (int(frame), int(marker))

    return spoil


def _offset(markers):
    return markers + 1e200, (0, 0)


def _subnormal(markers):
    # Every sample a distinct subnormal: none at (0, 0, 0), none finite squared.
    steps = np.arange(1, markers.size + 1, dtype=float).reshape(markers.shape)
    return steps * 5e-324, None


def _nan_and_huge(markers):
    spoilt = markers.copy()
    spoilt[3, 0, 0] = 1e300
    spoilt[8, 2, 1] = np.nan
    return spoilt, (8, 2)  # the NaN is named first, as the samples are read


#: Per hostile input, what it does to one array ``(N, n, 3)``: the spoilt array and the
#: ``(frame, marker)`` the error must name (``None``: the array is named, no sample).
HOSTILE = {
    "one-1e154": _set(1e154, 3, 0, 0),
    "one-1e155": _set(1e155, 3, 0, 0),
    "one-1e200": _set(1e200, 3, 0, 0),
    "one-1e300": _set(1e300, 3, 0, 0),
    "one--1.7e308": _set(-1.7e308, 3, 0, 0),
    "two-frames-+-1e300": lambda m: (_set(-1e300, 9, 2, 0)(_set(1e300, 5, 1, 2)(m)[0])[0], (5, 1)),
    "whole-marker-1e200": _set(1e200, slice(None), 1),
    "whole-frame-1e200": _set(1e200, 7),
    "offset-1e200": _offset,
    "subnormal": _subnormal,
    "nan-and-1e300": _nan_and_huge,
}


def _arrays(kind: str, hostile: str) -> tuple[tuple[np.ndarray, ...], str, tuple | None]:
    """The arrays of ``kind`` with the last spoilt by ``hostile``, its name and the sample
    the error must name."""
    arrays = _two_segments() if kind == "joint_center" else (_one_segment(kind),)
    spoilt, sample = HOSTILE[hostile](arrays[-1])
    return (*arrays[:-1], spoilt), validation.ARRAY_NAMES[kind][-1], sample


def _assert_named(error: BaseException, name: str, sample: tuple | None) -> None:
    assert isinstance(error, ValueError), f"{type(error).__name__}: {error}"
    assert re.search(rf"\b{name}\b", str(error)), str(error)
    if sample is not None:
        frame, marker = sample
        assert f"marker {marker}, frame {frame}" in str(error), str(error)


def _raised(call) -> BaseException:
    try:
        call()
    except Exception as error:
        return error
    raise AssertionError("accepted")


ENTRIES = {
    "check_input": lambda kind, arrays: validation.check_input(kind, arrays),
    "check_markers": lambda kind, arrays: validation.check_markers(
        arrays[-1], name=validation.ARRAY_NAMES[kind][-1]
    ),
    "assess": lambda kind, arrays: support.assess(kind, arrays),
    "public-fit": lambda kind, arrays: PUBLIC_FITS[kind](*arrays),
    "public-screen": lambda kind, arrays: jointbench.screen(*arrays),
    "find_artefacts": lambda kind, arrays: screening.find_artefacts(arrays[-1], LABELS, "markers"),
    "screen": lambda kind, arrays: screening.screen(arrays[-1], LABELS, "markers"),
}

#: The labels the screen is given, in its messages for the marker.
LABELS = ("0", "1", "2")

#: The entries that take no unit: subnormal markers are a cluster there like any other.
SCALE_FREE = ("check_markers", "public-screen", "find_artefacts", "screen")

PUBLIC_FITS = {
    "center": jointbench.fit_center,
    "axis": jointbench.fit_axis,
    "joint_center": jointbench.fit_joint_center,
}


def _method_entries(kind: str) -> dict:
    entries = {}
    for name in registry.methods(kind):
        entries[f"{name}-checked"] = lambda k, a, n=name: registry.get(k, n)(*a)
        entries[f"{name}-bare"] = lambda k, a, n=name: registry.get(k, n, checked=False)(*a)

        def many(k, a, n=name, checked=True):
            (outcome,) = registry.many(k, n, checked=checked)(*(array[None] for array in a))
            if isinstance(outcome, Exception):
                raise outcome
            return outcome

        entries[f"{name}-many"] = many
        entries[f"{name}-many-bare"] = lambda k, a, n=name, many=many: many(k, a, n, False)
    return entries


CASES = [
    (kind, entry, hostile)
    for kind in validation.ARRAY_NAMES
    for entry in (*ENTRIES, *_method_entries(kind))
    for hostile in HOSTILE
]


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize(("kind", "entry", "hostile"), CASES)
def test_every_entry_refuses_hostile_coordinates_naming_array_marker_and_frame(
    kind, entry, hostile
):
    arrays, name, sample = _arrays(kind, hostile)
    call = ENTRIES.get(entry) or _method_entries(kind)[entry]
    if hostile == "subnormal" and (
        entry in SCALE_FREE or (entry, kind) == ("check_input", "joint_center")
    ):
        # Subnormal samples are finite samples, and their distances square to 0: a cluster at
        # one point, left to the checks of the markers each method needs (below); the screen
        # is scale-free.
        call(kind, arrays)
        return
    if (entry, hostile) == ("assess", "subnormal"):
        # The verdict takes no unit (its callers check the cluster's size): markers at a
        # point within rounding are judged as that, and say it.
        (stated, *_) = support.assess(kind, arrays).warnings
        assert stated.startswith("not verified: no 3 non-collinear markers"), stated
        return
    if entry in ("find_artefacts", "screen"):
        # The screen reads NaN as a gap: it names the first sample beyond the bound, by label.
        error = _raised(lambda: call(kind, arrays))
        assert isinstance(error, ValueError), f"{type(error).__name__}: {error}"
        frame, marker, *_ = first_beyond(arrays[-1])
        assert f"marker {LABELS[marker]} has a coordinate of " in str(error), str(error)
        assert f" at frame {frame} (" in str(error), str(error)
        return
    _assert_named(_raised(lambda: call(kind, arrays)), name, sample)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("hostile", [h for h in HOSTILE if h != "subnormal"])
@pytest.mark.parametrize("kind", list(validation.ARRAY_NAMES))
def test_a_recording_with_hostile_coordinates_is_refused_naming_label_and_frame(kind, hostile):
    """Through a recording the arrays are named by their labels and frames by the file's
    numbers; huge samples are refused (or screened as artefacts) whichever catches them."""
    arrays, _, sample = _arrays(kind, hostile)
    labels = [f"{segment}{i}" for segment in ("P", "D")[-len(arrays) :] for i in range(3)]
    recording = jointbench.Recording(labels, np.concatenate(arrays, axis=1))
    moving, reference = ",".join(labels[-3:]), (",".join(labels[:3]) if len(arrays) > 1 else None)
    error = _raised(lambda: jointbench.fit(recording, kind, moving, reference))
    assert isinstance(error, ValueError), f"{type(error).__name__}: {error}"
    if sample is not None and not np.isnan(arrays[-1][sample]).any():
        assert f"D{sample[1]}" in str(error), str(error)


@pytest.mark.parametrize("n_frames", [3, 120, 100_000])
def test_the_bound_keeps_every_sum_of_the_checks_finite_and_passes_a_distant_origin(n_frames):
    """At the bound, the largest the checks' arithmetic reaches, the product of two sums of
    squared deviations, is finite; just past it a sample is refused; a cluster 1e6 mm from the
    origin (tests/test_centre_checked_pinned.py) is nowhere near it."""
    bound = largest_coordinate(n_frames * 3)
    distance_sums = 12.0 * n_frames * 3 * bound**2
    assert np.isfinite(distance_sums * distance_sums)
    assert bound > 1e70
    markers = np.random.default_rng(5).normal(scale=50.0, size=(n_frames, 3, 3))
    markers[1, 2] = [bound, -bound, bound]
    validation.check_markers(markers)
    # Every coordinate at the bound's scale: the straight-line test's sums stay finite.
    angles = np.linspace(0.0, 3.0, n_frames)[:, None] + np.arange(3.0)
    curved = bound * np.stack([np.cos(angles), np.sin(angles), np.sin(2 * angles)], -1)
    validation.check_rotates(curved)
    markers[1, 2, 1] = -np.nextafter(bound, np.inf)
    with pytest.raises(ValueError, match=r"^markers has a coordinate of .* at marker 2, frame 1 "):
        validation.check_markers(markers)
