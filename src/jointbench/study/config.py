"""The study configuration: loading, validation, the condition grid and its file names."""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from importlib import resources
from importlib.abc import Traversable
from pathlib import Path

import jsonschema
import yaml

from jointbench.study.studies import get_study
from jointbench.study.studies import study_names as registered_studies

__all__ = [
    "condition_id",
    "conditions",
    "estimator_names",
    "load_config",
    "parse_condition_id",
    "study_names",
    "validate_against",
    "validate_config",
]

SCHEMA_PATH = resources.files("jointbench.schemas").joinpath("config.schema.yaml")


def validate_against(document: Mapping, schema_path: str | Path | Traversable, what: str) -> None:
    """Raise ``ValueError`` naming ``what`` and the offending path when ``document`` does not
    match the JSON schema (YAML) at ``schema_path``."""
    if isinstance(schema_path, str):
        schema_path = Path(schema_path)
    schema = yaml.safe_load(schema_path.read_text())
    try:
        jsonschema.validate(dict(document), schema)
    except jsonschema.ValidationError as error:
        where = "/".join(map(str, error.absolute_path)) or "(top level)"
        raise ValueError(f"{what} error at {where}: {error.message}") from None


def validate_config(config: Mapping, schema_path: str | Path | Traversable = SCHEMA_PATH) -> None:
    """Raise ``ValueError`` when ``config`` does not match the JSON schema, or names a study
    that is not registered."""
    validate_against(config, schema_path, "config")
    unknown = sorted(set(config["studies"]) - set(registered_studies()))
    if unknown:
        raise ValueError(
            f"config error at studies: unknown studies {unknown}; registered studies are "
            f"{', '.join(registered_studies())} (a study outside the package is added by listing "
            "its module under extensions)"
        )


def load_config(path: str | Path, schema_path: str | Path | Traversable = SCHEMA_PATH) -> dict:
    """Read and validate a YAML config."""
    config = yaml.safe_load(Path(path).read_text())
    validate_config(config, schema_path)
    return config


def study_names(config: Mapping) -> list[str]:
    """Studies switched on in the config, in config order."""
    return [name for name, study in config["studies"].items() if study.get("enabled", True)]


def conditions(config: Mapping, study: str) -> list[dict[str, object]]:
    """Every cell of a study's grid, as dicts in the study's key order."""
    keys = get_study(study).grid_keys
    grid = config["studies"][study]["grid"]
    missing = [key for key in keys if key not in grid]
    if missing:
        raise ValueError(f"config: study {study!r} grid lacks {missing}")
    return [
        dict(zip(keys, values, strict=True))
        for values in itertools.product(*(grid[k] for k in keys))
    ]


def condition_id(condition: Mapping[str, object]) -> str:
    """File-name form of a condition, e.g. ``marker_set-M__rom_deg-5__noise_mm-1.0``."""
    return "__".join(f"{key}-{value}" for key, value in condition.items())


def parse_condition_id(config: Mapping, study: str, identifier: str) -> dict[str, object]:
    """The grid condition named ``identifier`` by :func:`condition_id`, with config types."""
    for condition in conditions(config, study):
        if condition_id(condition) == identifier:
            return condition
    raise ValueError(f"{identifier!r} is not a condition of study {study!r} in this config")


def estimator_names(config: Mapping, study: str, *, source: str = "all") -> list[str]:
    """Estimators listed for a study: ``"builtin"`` (run by the generic rule), ``"external"``
    (each written by its own rule) or ``"all"``."""
    settings = config["studies"][study]
    builtin = list(settings.get("estimators", []))
    external = list(settings.get("external_estimators", []))
    return {"builtin": builtin, "external": external, "all": builtin + external}[source]
