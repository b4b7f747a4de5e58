"""A protocol field set to a value no motion-capture study can have stops the run before any job,
naming ``studies.<study>.protocol.<field>`` and the value; a value the check accepts simulates
finite data.

Every number of every protocol field of every package study is given hostile values (huge,
tiny, negative, zero, inf and NaN; one number of a field, or all of them) and then, by
hypothesis, any float or integer: the config's check either passes or raises ``ValueError``
naming the key, never another exception; and where it passes, the study's simulator gives
finite markers in the lab for the grid's first and last conditions (the smallest and the
largest values of every grid key), so no job starts that only fails, or writes inf or NaN.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import numbers

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from workflow_copy import ROOT, refused_dry_run

from jointbench.configuration import config as study_config
from jointbench.configuration.studies import get_study
from jointbench.simulate import hinge
from jointbench.simulate.ranges import LAB_MM

STUDIES = ("cmc", "hinge", "hip", "hip_sta")
HOSTILE = (
    -0.0,
    1e300,
    -1e300,
    1e30,
    -1e30,
    10**13,
    1e-300,
    -1e-300,
    0,
    -1,
    math.inf,
    -math.inf,
    math.nan,
)


@pytest.fixture(scope="module")
def config():
    return study_config.load_config(ROOT / "config" / "config.yaml")


def _default_fields(study: str) -> dict[str, object]:
    """The study's protocol fields as the config sets them, each with its default value (the
    hinge's under ``all``, as the knee has them)."""
    protocol = get_study(study).protocol()
    if study == "hinge":
        protocol = protocol.joints["knee"]
    return {f.name: getattr(protocol, f.name) for f in dataclasses.fields(protocol)}


def _is_number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _has_number(value: object) -> bool:
    if _is_number(value):
        return True
    if isinstance(value, dict):
        return any(_has_number(v) for v in value.values())
    if isinstance(value, tuple | list | np.ndarray):
        return any(_has_number(v) for v in value)
    return False


def _poisoned(value: object, hostile: object, every: bool) -> tuple[object, bool]:
    """``value`` as YAML would give it (lists for tuples) with its first number, or every
    number, replaced by ``hostile``; and whether one was replaced."""
    if _is_number(value):
        return hostile, True
    if isinstance(value, dict):
        items, done = {}, False
        for key, item in value.items():
            items[key], hit = (
                (item, False) if done and not every else _poisoned(item, hostile, every)
            )
            done = done or hit
        return items, done
    if isinstance(value, tuple | list | np.ndarray):
        items, done = [], False
        for item in value:
            new, hit = (item, False) if done and not every else _poisoned(item, hostile, every)
            items.append(new)
            done = done or hit
        return items, done
    return value, False


NUMERIC_FIELDS = [
    (study, name)
    for study in STUDIES
    for name, value in _default_fields(study).items()
    if _has_number(value)
]


FIELD_IDS = [f"{study}.{field}" for study, field in NUMERIC_FIELDS]


def _overrides(study: str, field: str, hostile: object, every: bool) -> dict:
    value, _ = _poisoned(_default_fields(study)[field], hostile, every)
    return _written(study, field, value)


def _written(study: str, field: str, value: object) -> dict:
    """The protocol overrides writing ``field`` as ``value``: the hinge's under ``all``, with
    a motion that reads it where the default does not (the check refuses a field written for
    a motion that does not read it, before its value)."""
    if study != "hinge":
        return {field: value}
    readers = [motion for motion, fields in hinge.MOTION_FIELDS.items() if field in fields]
    return {"all": {field: value, **({"motion": readers[0]} if readers else {})}}


def _with_protocol(config: dict, study: str, overrides: dict) -> dict:
    new = copy.deepcopy(config)
    new["studies"][study]["protocol"] = overrides
    return new


def _key_of(message: str) -> str:
    """The key a refusal names: ``config: <key>: <why>``."""
    assert message.startswith("config: "), message
    return message.removeprefix("config: ").split(": ", 1)[0]


#: [mm] Where every simulated marker lies: a joint within LAB_MM of the origin, moved by
#: displacements of at most LAB_MM, carries its markers within SEGMENT_MM, and the noise and
#: artefact are bounded by the farthest marker's distance; ten times LAB_MM holds them all.
IN_THE_LAB_MM = 10 * LAB_MM


def _finite_trials(config: dict, study: str) -> None:
    """The study's first and last conditions simulate finite markers in the lab, one trial
    each."""
    spec = get_study(study)
    protocol = spec.protocol(config["studies"][study].get("protocol"))
    cells = study_config.conditions(config, study)
    for condition in (cells[0], cells[-1]):
        trials = spec.simulate(condition, protocol, [np.random.default_rng(0)])
        for segment, markers in trials.segments.items():
            assert np.all(np.isfinite(markers)), (study, condition, segment)
            assert np.abs(markers).max() <= IN_THE_LAB_MM, (study, condition, segment)


def _refused_or_finite(config: dict, study: str, field: str, overrides: dict) -> None:
    """The check refuses ``overrides`` naming ``field`` (a field of the frames too, refused by
    the check of a condition's frames; or a grid value beyond a bound the protocol sets,
    naming the protocol as its source), or passes and the study simulates finite data. The
    hinge's field, written under ``all``, is named there."""
    candidate = _with_protocol(config, study, overrides)
    try:
        study_config.check_config(candidate)
    except ValueError as error:
        message = str(error)
        key, protocol = _key_of(message), f"studies.{study}.protocol"
        written = f"all.{field}" if study == "hinge" else field
        if key.startswith(f"studies.{study}.grid."):
            assert f"the bound {protocol} sets" in message, message
        else:
            assert key.startswith(protocol) and written in key, message
        return
    _finite_trials(candidate, study)


# An overflow or a NaN met on the way is arithmetic on a value no check refused: an error here.
@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("every", [False, True], ids=["one number", "every number"])
@pytest.mark.parametrize("hostile", HOSTILE, ids=repr)
@pytest.mark.parametrize(("study", "field"), NUMERIC_FIELDS, ids=FIELD_IDS)
def test_a_hostile_protocol_value_is_refused_naming_its_key_or_simulates_finite_data(
    config, study, field, hostile, every
):
    _refused_or_finite(config, study, field, _overrides(study, field, hostile, every))


_ANY_NUMBER = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-1e6, max_value=1e6),
    st.integers(min_value=-(10**15), max_value=10**15),
)


@pytest.mark.filterwarnings("error::RuntimeWarning")
@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_any_number_in_any_protocol_field_is_refused_naming_its_key_or_simulates_finite_data(
    config, data
):
    study, field = data.draw(st.sampled_from(NUMERIC_FIELDS))
    value = data.draw(_ANY_NUMBER)
    every = data.draw(st.booleans())
    _refused_or_finite(config, study, field, _overrides(study, field, value, every))


@pytest.mark.parametrize(("study", "field"), NUMERIC_FIELDS, ids=FIELD_IDS)
def test_each_protocol_fields_default_passes_the_check(config, study, field):
    """The hostile values are all that is refused: the default, written out, passes."""
    value = _default_fields(study)[field]
    overrides = _written(study, field, _as_yaml(value))
    study_config.check_config(_with_protocol(config, study, overrides))


def _as_yaml(value: object) -> object:
    if isinstance(value, dict):
        return {key: _as_yaml(item) for key, item in value.items()}
    if isinstance(value, tuple | list | np.ndarray):
        return [_as_yaml(item) for item in value]
    return value


@pytest.mark.pipeline
def test_a_dry_run_stops_before_any_job_naming_the_protocol_field(tmp_path):
    """The skin-marker study's joint a few hundred digits out: before the check, its pose fits
    failed inside the simulate job ("SVD did not converge")."""
    overlay = {"studies": {"hip_sta": {"protocol": {"joint_mm": [1e300, -90.0, 900.0]}}}}
    message = refused_dry_run(tmp_path, overlay)
    assert "config: studies.hip_sta.protocol.joint_mm[0]: must be a number" in message, message
    assert "1e+300" in message, message[-2000:]
