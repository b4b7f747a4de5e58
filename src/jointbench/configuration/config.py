"""The study configuration: loading, validation, the condition grid and its file names."""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import itertools
import json
import numbers
import re
from collections.abc import Hashable, Iterator, Mapping, Sequence
from importlib import resources
from importlib.abc import Traversable
from pathlib import Path

import yaml

from jointbench import declared
from jointbench.configuration.bounds import field_values, study_problem, translation_problem
from jointbench.configuration.extensions import load_extensions
from jointbench.configuration.studies import get_study, method_kind
from jointbench.configuration.studies import study_names as registered_studies
from jointbench.estimators import registry
from jointbench.running import timelimit
from jointbench.simulate import KINDS, Study

__all__ = [
    "CONFIG_VALUES",
    "MAX_TRIALS",
    "ConfigError",
    "SchemaError",
    "check_config",
    "check_config_values",
    "check_external_kind",
    "check_schema",
    "check_sources",
    "condition_id",
    "conditions",
    "config_values",
    "estimator_names",
    "external_kind",
    "load_config",
    "open_config",
    "open_config_files",
    "open_sources",
    "ordered_settings",
    "parse_condition_id",
    "read_config_file",
    "read_configs",
    "read_sources",
    "read_yaml",
    "sources_named",
    "study_names",
    "validate_against",
    "validate_config",
    "verdict_seeds",
]

SCHEMA_PATH = resources.files("jointbench.schemas").joinpath("config.schema.yaml")

# Trials per condition. At 10 000 the Monte Carlo standard error of a mean error is 1 % of the
# trials' spread, finer than any published tolerance; the largest dataset (hip: 1200 frames of
# 6 markers) is then 72 million rows, about what one job can hold in memory. More is a typo.
MAX_TRIALS = 10_000
#: Frames of a condition's trials together: those of the largest dataset above (1200 frames
#: times :data:`MAX_TRIALS`), what one job can hold. A protocol whose trials hold more (a
#: ``duration_s`` or ``fps`` typed a few digits too long) is a typo, refused before any check
#: lays out its frames.
MAX_CONDITION_FRAMES = 1200 * MAX_TRIALS


# The safe loader, in C when PyYAML has it (10x faster than Python's on the published-values
# files, which every render job reads).
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def read_yaml(text: str) -> object:
    """A YAML document with the safe loader."""
    return yaml.load(text, Loader=_LOADER)


class ConfigError(ValueError):
    """A config refused at some of its keys. ``paths``: each the keys (and list indices) from
    the top to a value at fault, whose sources a run of several config files names
    (:func:`sources_named`); ``()`` is the config as a whole, which no one source sets.
    ``keyed``: the sources name each key, even where one source sets them all, for a refusal
    whose words also name keys that are not at ``paths`` (a named protocol's overlay's)."""

    def __init__(self, message: str, paths: Sequence[Sequence] = (), *, keyed: bool = False):
        super().__init__(message)
        self.paths = tuple(tuple(path) for path in paths)
        self.keyed = keyed


class SchemaError(ConfigError):
    """A document that does not match its schema. ``path``: the keys (and list indices) from
    the top to the value at fault; for a key the schema does not allow, down to that key.
    ``of_name``: the key's name is refused (a ``propertyNames`` pattern), not its value."""

    def __init__(self, message: str, path: Sequence = (), *, of_name: bool = False) -> None:
        super().__init__(message, [path])
        self.path = tuple(path)
        self.of_name = of_name


def validate_against(document: Mapping, schema_path: str | Path | Traversable, what: str) -> None:
    """Raise ``ValueError`` naming ``what`` and the offending path when ``document`` does not
    match the JSON schema (YAML) at ``schema_path``, whose ``integer`` is a Python ``int``
    (:func:`_is_integer`), not a whole float."""
    if isinstance(schema_path, str):
        schema_path = Path(schema_path)
    # Imported here: only the workflow's start checks the config, not each job.
    import jsonschema

    schema = read_yaml(schema_path.read_text())
    base = jsonschema.validators.validator_for(schema)
    # JSON Schema counts 3.0 as an integer. A count or seed written so (a decimal point left in,
    # or Snakemake's --config typing base_seed=1e3 as 1000.0) is refused, as the grid's and the
    # protocol's integers refuse it, not carried as a float into the jobs' parameters.
    strict = jsonschema.validators.extend(
        base, type_checker=base.TYPE_CHECKER.redefine("integer", _is_integer)
    )
    try:
        jsonschema.validate(dict(document), schema, cls=strict)
    except jsonschema.ValidationError as error:
        where = "/".join(map(str, error.absolute_path)) or "(top level)"
        raise SchemaError(
            f"{what} error at {where}: {error.message}{_name_rule(error)}",
            _at_fault(error),
            of_name=_of_name(error),
        ) from None


def _at_fault(error) -> tuple:
    """The keys leading to what the jsonschema ``error`` is about: its path, and for a key the
    schema does not allow (a misspelt one, or a name its ``propertyNames`` refuses, whose
    error's instance is the name), that key, which the path stops above."""
    path = tuple(error.absolute_path)
    allowed = error.schema.get("properties", {}) if isinstance(error.schema, Mapping) else {}
    if error.validator == "additionalProperties" and isinstance(error.instance, Mapping):
        extra = [key for key in error.instance if key not in allowed]
        return (*path, *extra[:1])
    if _of_name(error):
        return (*path, error.instance)
    return path


def _of_name(error) -> bool:
    """Whether the jsonschema ``error`` refuses a key's name (``propertyNames``), whose
    instance is then the name."""
    return "propertyNames" in error.absolute_schema_path


def _name_rule(error) -> str:
    """``: `` and what a name may be, the ``description`` of the ``propertyNames`` schema that
    refuses a key's name in the jsonschema ``error`` (a pattern alone says it to few readers);
    else nothing."""
    rule = error.schema.get("description") if isinstance(error.schema, Mapping) else None
    return f": {rule}" if rule and _of_name(error) else ""


def _is_integer(_checker: object, instance: object) -> bool:
    """JSON Schema's ``integer``, of Python's ``int`` alone: not ``True``, nor ``3.0``."""
    return isinstance(instance, int) and not isinstance(instance, bool)


def validate_config(config: Mapping, schema_path: str | Path | Traversable = SCHEMA_PATH) -> None:
    """Raise ``ValueError`` when ``config`` does not match the JSON schema, or names a study
    that is not registered."""
    validate_against(config, schema_path, "config")
    _check_studies_registered(config)


def check_schema(config: Mapping) -> None:
    """``config`` against its schema (:func:`validate_against`), a study not registered named
    first: an overlay's misspelt study (``studies: {cmx: {trials: 5}}``) is a study without a
    grid to the schema, but the mistake is its name. Before it, a name no study may have
    (``knee.v2``), with what a name may be: registering one would not mend it. With
    ``extensions`` listed, a study may be theirs, and none is imported from a config that fails
    the schema: the schema's error is given, saying which studies are not built in.
    ``ValueError`` in one line naming the key.

    The workflow runs it before Snakemake's own validation, whose error leads with a dump of
    the schema; :func:`open_config` runs it first."""
    studies = config.get("studies")
    if not isinstance(studies, Mapping):
        validate_against(config, SCHEMA_PATH, "config")
        return
    try:
        validate_against(config, SCHEMA_PATH, "config")
    except SchemaError as error:
        unknown = _unknown_studies(config)
        # A name the schema refuses is the mistake, wherever the study would come from, and
        # whether or not one is registered: no study may have it.
        if not unknown or error.of_name:
            raise
        if not config.get("extensions"):
            _check_studies_registered(config)
        raise SchemaError(
            f"{error} ({', '.join(map(repr, unknown))} is not a built-in study: built in are "
            f"{', '.join(registered_studies())}; another must come from the extensions)",
            error.path,
        ) from None
    if not config.get("extensions"):
        _check_studies_registered(config)


def _unknown_studies(config: Mapping) -> list[str]:
    return sorted(set(config["studies"]) - set(registered_studies()))


def _check_studies_registered(config: Mapping) -> None:
    """Raise ``ValueError`` naming the studies of ``config`` that no module registered."""
    unknown = _unknown_studies(config)
    if unknown:
        raise SchemaError(
            f"config error at studies: unknown studies {unknown}; registered studies are "
            f"{', '.join(registered_studies())} (a study outside the package is added by listing "
            "its module under extensions)",
            ("studies", unknown[0]),
        )


def load_config(path: str | Path) -> dict:
    """A YAML config opened as a run opens it (:func:`open_config_files`)."""
    return dict(open_config_files([path]))


def open_config_files(paths: Sequence[str | Path], base: str | Path = ".") -> Mapping:
    """The config of the files ``paths``, each over the ones before (:func:`read_sources`),
    opened as a run opens it (:func:`open_config`); an error at a key names the files that set
    it (:func:`sources_named`)."""
    return open_sources(read_sources(paths), base)


def open_sources(sources: Sequence[tuple[str, Mapping]], base: str | Path = ".") -> Mapping:
    """The config ``sources`` (``(name, document)``, each over the ones before) make, opened as
    a run opens it (:func:`open_config`); an error at a key names the sources that set it
    (:func:`sources_named`)."""
    with sources_named(sources):
        return open_config(merged_sources(sources), base)


def open_config(config: Mapping, base: str | Path = ".") -> Mapping:
    """What a run starts from, in the workflow and on the command line alike: ``config``
    checked against its schema (:func:`validate_against`), its extensions loaded (relative to
    ``base``) and registered, then checked against the registries (the studies it names, and
    :func:`check_config`); ``ValueError`` naming the key, or the extension's file. Returns
    ``config``, its studies now listed in the registry's order (:func:`study_names`) and each
    study's settings in one order (:func:`ordered_settings`)."""
    # The schema first: a misspelt key is named as such, not hidden behind an extension's import
    # error, and no extension is imported from a config that is not the one meant.
    check_schema(config)
    try:
        load_extensions(config, base)
    except ValueError as error:
        # Its words name the entry and its file; the list is what a config file sets.
        raise ConfigError(str(error), [("extensions",)]) from error
    _check_studies_registered(config)
    check_config(config)
    # Jobs' parameters list the studies (a job's settings of every study): in one order,
    # whatever order the config gives them, a reorder reruns nothing.
    listed = config["studies"]
    config["studies"] = {
        study: ordered_settings(get_study(study), listed[study])
        for study in registered_studies()
        if study in listed
    }
    return config


def ordered_settings(spec: Study, settings: Mapping) -> dict:
    """A study's checked ``settings`` listed in one order, whichever order the config lists
    their keys in: sorted, the grid's in the study's own order, ``spec.grid_keys``, and each
    estimator's options sorted by estimator and by option; lists as listed.

    No job reads meaning into these keys' places: the grid's conditions, their names and their
    order follow the study's key order (:func:`conditions`), an estimator's options are keyword
    arguments, and the other keys are looked up by name. The jobs' parameters carry these
    mappings, so a run opens its config so ordered (:func:`open_config`): however the keys are
    listed, the parameters are the same and a reorder reruns no job. A list's order is kept
    (the grid values' orders the conditions), and so is the protocol's, whose added marker sets
    a paper lists in the order given."""
    ordered = {key: settings[key] for key in sorted(settings)}
    ordered["grid"] = {key: settings["grid"][key] for key in spec.grid_keys}
    if "options" in settings:
        options = settings["options"]
        ordered["options"] = {
            method: {name: options[method][name] for name in sorted(options[method])}
            for method in sorted(options)
        }
    return ordered


def named_overlays(config: Mapping, base: str | Path = ".") -> dict[str, Mapping]:
    """The config overlay of each named protocol of ``config["sensitivity"]["named"]`` (name ->
    YAML file, relative to ``base``), by name; ``ValueError`` naming the key and the file when
    one is missing, is no mapping, or makes with ``config`` a config that would not run
    (:func:`validate_against`, :func:`check_config`). The workflow reads them when it starts,
    whatever its target, so a mistake in one stops it before any job instead of after the main
    run."""
    overlays = {}
    for name, path in dict(config.get("sensitivity", {}).get("named", {})).items():
        # The key naming the overlay, which a config file sets: its words name the overlay.
        at = [("sensitivity", "named", name)]
        where = f"config error at {declared.keys(at)} ({path})"
        try:
            document = read_config_file(Path(base) / path, where)
        except ValueError as error:
            raise ConfigError(str(error), at) from None
        merged = _merged(config, document)
        try:
            # A key at fault that the overlay sets is named with it, as a config file's is.
            with sources_named([(str(path), document)]):
                validate_against(merged, SCHEMA_PATH, "config")
                check_config(merged)
        except ValueError as error:
            raise ConfigError(f"{where}: {error}", at, keyed=True) from None
        overlays[name] = document
    return overlays


def read_configs(paths: Sequence[str | Path]) -> dict:
    """The config of YAML files read in order, each updating the ones before as Snakemake's
    ``--configfile`` does: a mapping merged key by key, any other value replaced; checked
    against the schema, an error naming the file that set the key (:func:`check_sources`)."""
    sources = read_sources(paths)
    config = merged_sources(sources)
    check_sources(config, sources)
    return config


def read_sources(paths: Sequence[str | Path]) -> list[tuple[str, Mapping]]:
    """``(path, document)`` of each config file of ``paths``, in order, each read as
    :func:`read_config_file` reads it."""
    return [(str(path), read_config_file(Path(path), f"config file {path}")) for path in paths]


def merged_sources(sources: Sequence[tuple[str, Mapping]]) -> dict:
    """The config ``sources`` (``(name, document)``) make, each over the ones before."""
    config: dict = {}
    for _name, document in sources:
        config = _merged(config, document)
    return config


def check_sources(config: Mapping, sources: Sequence[tuple[str, Mapping]]) -> None:
    """``config``, made of ``sources`` (``(name, document)``: a config file's path, or
    ``--config``, each over the ones before), against its schema (:func:`check_schema`); the
    error, in one line, names the key and the sources that set it (:func:`sources_named`)."""
    with sources_named(sources):
        check_schema(config)


@contextlib.contextmanager
def sources_named(sources: Sequence[tuple[str, Mapping]]) -> Iterator[None]:
    """Within it, a :class:`ConfigError` names, after its own words, the ``sources``
    (``(name, document)``, each over the ones before) that set the keys it is at
    (`` (set in b.yaml)``, :func:`_set_in`): among several config files, the key alone does not
    say which to mend. Every check of a config, before or after its schema's, is named so."""
    try:
        yield
    except ConfigError as error:
        paths = [path for path in error.paths if path]
        named = _set_in(paths, sources, keyed=error.keyed)
        if not named:
            raise
        raise ConfigError(
            f"{error} ({named}{_given_as_text(paths, sources)})", error.paths
        ) from None


# A text that begins as a number does (a sign, a dot or a digit): a number meant, given as text.
_NUMBER_START = re.compile(r"[-+]?\.?[0-9]")


def _given_as_text(paths: Sequence[tuple], sources: Sequence[tuple[str, Mapping]]) -> str:
    """``, as the text '7mm': ...``, how to write a number in ``--config``, where the value at
    one of ``paths`` is the text of a number (:data:`_NUMBER_START`), or holds one, and the
    ``--config`` values set it last: ``--config`` leaves text what is written in quotes or
    with a unit (:func:`config_values`), which the refusal's own words do not tell from a
    number. Else nothing."""
    values = dict(sources).get(CONFIG_VALUES)
    for path in paths:
        setters = _setters(path, sources)
        if values is None or not setters or setters[-1] != CONFIG_VALUES:
            continue
        value = _value_at(values, path)[1]
        texts = [
            item
            for item in (value if isinstance(value, list) else [value])
            if isinstance(item, str) and _NUMBER_START.match(item)
        ]
        if texts:
            return (
                f", as the text {texts[0]!r}: a number is read from --config where it is "
                "written alone, unquoted and with no unit (--config base_seed=7, or "
                "studies='{cmc: {trials: 7}}')"
            )
    return ""


def _set_in(
    paths: Sequence[tuple], sources: Sequence[tuple[str, Mapping]], *, keyed: bool = False
) -> str:
    """Which of ``sources`` set the keys at ``paths`` (:func:`_setters`): ``set in b.yaml``
    where every key a source sets is set by the same ones (a key no source sets, a default,
    aside) and not ``keyed``, else each key with its own (``noise_sd_mm set in a.yaml;
    knee.markers_mm set in b.yaml``, the keys written as the refusal writes them,
    :func:`~jointbench.declared.key_texts`); empty where no source sets any."""
    if not paths:
        return ""
    texts = declared.key_texts(paths)
    setters = [(text, _setters(path, sources)) for text, path in zip(texts, paths, strict=True)]
    setters = [(text, names) for text, names in setters if names]
    if not keyed and len({tuple(names) for _, names in setters}) == 1:
        return f"set in {', '.join(setters[0][1])}"
    return "; ".join(f"{text} set in {', '.join(names)}" for text, names in setters)


def _setters(path: Sequence, sources: Sequence[tuple[str, Mapping]]) -> list[str]:
    """The names of the ``sources`` whose values make the config's value at ``path``: the
    last that sets it to anything but a mapping and those after it that merge a mapping over
    that; none where no source holds ``path``."""
    setters: list[str] = []
    for name, document in sources:
        found, value = _value_at(document, path)
        if found:
            setters = [*setters, name] if isinstance(value, Mapping) else [name]
    return setters


def _value_at(document: object, path: Sequence) -> tuple[bool, object]:
    """``(True, value)`` at ``path`` (keys and list indices) in ``document``, or ``(False,
    None)`` where it has none."""
    for step in path:
        if isinstance(document, Mapping) and step in document:
            document = document[step]
        elif isinstance(document, list) and isinstance(step, int) and step < len(document):
            document = document[step]
        else:
            return False, None
    return True, document


def check_config_values(entries: Sequence[str]) -> None:
    """Refuse, naming the entry, a ``--config`` value (``KEY=VALUE`` as typed, ``entries``)
    that Snakemake reads as a number other than YAML would, or than its digits show: it tries
    Python's ``int`` and ``float`` first, which read ``010`` as 10 (a config file, as 8) and
    drop underscores (``1_000``). A float's leading 0 (``010.5``) reads as its digits show,
    here and in a file alike."""
    for entry in entries:
        text = entry.partition("=")[2].strip()
        misread = {int: bool(_LEADING_ZERO.match(text)) or "_" in text, float: "_" in text}
        for parse in (int, float):
            try:
                number = parse(text)
            except ValueError:
                continue
            if not misread[parse]:
                break
            in_file = read_yaml(text)
            also = f", and in a config file as {in_file!r}" if in_file != number else ""
            raise ValueError(
                f"--config {entry}: {text} is read as {number!r}{also}; write the number in "
                "decimal digits, with no leading 0 or underscore"
            )


#: The name the config's sources give Snakemake's ``--config`` values (:func:`sources_named`).
CONFIG_VALUES = "--config"


def config_values(entries: Sequence[str], parsed: Mapping) -> dict:
    """The ``--config`` values (``KEY=VALUE`` as typed, ``entries``) as a config file holding
    them would be read: ``parsed``, Snakemake's reading of them, with each text in a mapping or
    list that YAML reads as a number or true/false read so. Snakemake reads a mapping or list
    value with YAML's base loader, which leaves every value in it text (``{trials: 7}`` gives
    ``'7'``); a value alone it reads as a number itself, where it is one (``base_seed=7``).
    A text written in quotes (``'7'``) or with a unit (``7mm``) stays text. ``ValueError``
    beginning with the entry for one that reads otherwise than written (:func:`_read_as_written`:
    ``010``, a key given twice, ``1e-3``, which YAML 1.1 reads as text). Each entry is read over
    the ones before, mappings merged key by key, as Snakemake merges them."""
    values: dict = {}
    for entry in entries:
        key, _, text = entry.partition("=")
        # Snakemake drops the quotes around a value, and reads a mapping or list by YAML alone.
        text = text.strip("'\"")
        given = yaml.load(text, Loader=yaml.BaseLoader) if text else None
        if isinstance(given, (Mapping, list)):
            value = _numbers_read(given, _read_as_written(text, f"--config {entry}"))
        else:
            value = parsed.get(key)
        values = _merged(values, {key: value})
    return values


def _numbers_read(given: object, read: object) -> object:
    """``given``, a value as YAML's base loader reads it (mappings, lists and texts), with each
    text that ``read``, the same value as the safe loader reads it, holds as a number or
    true/false replaced by that."""
    if isinstance(given, Mapping) and isinstance(read, Mapping):
        # The base loader keeps keys as text; the safe loader reads 1: as the number 1.
        keys = {str(key): key for key in read}
        return {
            key: _numbers_read(value, read.get(keys.get(key, key))) for key, value in given.items()
        }
    if isinstance(given, list) and isinstance(read, list) and len(given) == len(read):
        return [_numbers_read(item, again) for item, again in zip(given, read, strict=True)]
    if isinstance(given, str) and isinstance(read, (int, float)):
        return read
    return given


def read_config_file(path: Path, where: str) -> Mapping:
    """The mapping of config keys to values the YAML file ``path`` holds, or ``ValueError``
    in one line beginning with ``where`` (the file, or the key naming it): no such file, a
    folder, not UTF-8 text (the byte and its line), not YAML (where in the file, and why), no
    mapping, or YAML that reads otherwise than it is written (:func:`_read_as_written`: a
    number in another base, a key given twice, a value holding itself). An empty file, or one
    of comments alone, is refused as Snakemake's ``--configfile`` refuses it: it changes
    nothing, which is not what its writer meant."""
    if path.is_dir():
        raise ValueError(f"{where}: a folder, not a file")
    if not path.is_file():
        raise ValueError(f"{where}: no such file")
    text = _utf8_text(path.read_bytes(), where)
    try:
        # As Snakemake reads a config file: as JSON where it is JSON (where 1e-3 is a number),
        # else as YAML.
        document = _json_document(text, where)
        if document is _NOT_JSON:
            document = _read_as_written(text, where)
    except yaml.YAMLError as error:
        raise ValueError(f"{where}: not valid YAML{_yaml_error_place(error, text)}") from None
    if document is None:
        raise ValueError(
            f"{where}: empty: it holds no keys (a config file sets the keys it changes)"
        )
    if not isinstance(document, Mapping):
        raise ValueError(f"{where}: not a mapping of config keys to values")
    return document


_NOT_JSON = object()


def _json_document(text: str, where: str) -> object:
    """The JSON document ``text`` holds, or :data:`_NOT_JSON` where it is no JSON; a key given
    twice in one object refused naming ``where`` and the key's path (JSON readers keep the
    last alone)."""
    try:
        document = json.loads(text, object_pairs_hook=_JsonObject.of)
    except json.JSONDecodeError:
        return _NOT_JSON
    twice = _twice_in_json(document, ())
    if twice is not None:
        raise ValueError(
            f"{where}: {declared.key(twice)} is given twice in one object (the key "
            f"{twice[-1]!r}): JSON keeps the last alone; keep one"
        )
    return _plain(document)


class _JsonObject(dict):
    """A JSON object as read, with ``twice``, the first of its keys given more than once, or
    None: the reader, which builds the innermost objects first, does not know where one is."""

    twice: str | None = None

    @classmethod
    def of(cls, pairs: list[tuple[str, object]]) -> _JsonObject:
        read = cls()
        for key, value in pairs:
            if key in read and read.twice is None:
                read.twice = key
            read[key] = value
        return read


def _twice_in_json(document: object, path: tuple) -> tuple | None:
    """The path (keys and list indices from the top) of a key given twice in one object of the
    JSON ``document`` (of :class:`_JsonObject`): the first met walking it in the order
    written, an object before the values it holds; None where there is none."""
    if isinstance(document, _JsonObject):
        if document.twice is not None:
            return (*path, document.twice)
        items = document.items()
    elif isinstance(document, list):
        items = enumerate(document)
    else:
        return None
    found = (_twice_in_json(value, (*path, key)) for key, value in items)
    return next((twice for twice in found if twice is not None), None)


def _plain(document: object) -> object:
    """``document`` with each :class:`_JsonObject` a plain ``dict``."""
    if isinstance(document, dict):
        return {key: _plain(value) for key, value in document.items()}
    if isinstance(document, list):
        return [_plain(item) for item in document]
    return document


def _utf8_text(data: bytes, where: str) -> str:
    """``data`` as UTF-8 text, which Snakemake reads a config file as; else ``ValueError``
    naming ``where``, the first byte that is not and its line."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        line = data[: error.start].count(b"\n") + 1
        raise ValueError(
            f"{where}: not UTF-8 text: byte 0x{data[error.start]:02x} at line {line} "
            "(save the file as UTF-8)"
        ) from None


def _read_as_written(text: str, where: str) -> object:
    """The YAML document ``text``, read by the safe loader once its nodes are held to what
    they show (:func:`_check_nodes`, ``ValueError`` beginning with ``where``); None for a
    document of nothing."""
    loader = _LOADER(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node, _Place(where, (), 1), (), set())
        return loader.construct_document(node)
    finally:
        loader.dispose()


@dataclasses.dataclass(frozen=True)
class _Place:
    """Where a YAML node is: ``where`` (the file), the keys (and list indices) leading to it
    and the line that names it (its key's, or its own for a list item), from 1."""

    where: str
    keys: tuple
    line: int

    def at(self, key: object, line: int) -> _Place:
        return _Place(self.where, (*self.keys, key), line)

    def __str__(self) -> str:
        keys = ".".join(map(declared.key_name, self.keys)) or "(top level)"
        return f"{self.where}: {keys} at line {self.line}"


# The tags PyYAML resolves a plain scalar to; a number in decimal digits as YAML reads it, and
# a leading 0 Python reads past.
_INTEGER, _FLOAT, _MERGE, _VALUE, _DATE = (
    f"tag:yaml.org,2002:{tag}" for tag in ("int", "float", "merge", "value", "timestamp")
)
_DECIMAL = re.compile(r"[-+]?(0|[1-9][0-9]*)")
_TEXT = "tag:yaml.org,2002:str"
# A number as JSON and YAML 1.2 write one (sign, digits, a dot, an exponent): where YAML 1.1
# resolves it to text, an exponent lacked a dot before it or a sign, or a sign a digit after it.
_NUMBER_1_2 = re.compile(
    r"(?P<sign>[-+]?)(?P<mantissa>[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE](?P<exponent>[-+]?[0-9]+))?"
)
_LEADING_ZERO = re.compile(r"[-+]?0[0-9_]")


def _check_nodes(node: yaml.Node, place: _Place, holding: tuple, checked: set) -> None:
    """Refuse, with ``ValueError`` naming ``place``, a YAML node graph that reads otherwise
    than it is written: a number in a base its digits do not show (:func:`_number_problem`);
    a key given twice in one mapping (YAML keeps the last alone, so a value meant is dropped
    without a word); an alias inside the anchor it names, a value that would hold itself.
    ``holding``: the nodes above ``node``; ``checked``: the ids of nodes checked whole, each
    checked once however many aliases name it."""
    if any(node is above for above in holding):
        raise ValueError(f"{place}: an alias inside the value it names: a value cannot hold itself")
    if id(node) in checked:
        return
    if isinstance(node, yaml.ScalarNode):
        problem = _tag_problem(node) or _number_problem(node) or _date_problem(node)
        if problem:
            raise ValueError(f"{place}: {problem}")
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _check_nodes(item, place.at(index, item.start_mark.line + 1), (*holding, node), checked)
    else:
        # Each key as read, with the line and the text of its first: a mapping holds keys
        # equal as values once, whether written alike or not (yes and true, 1 and 1.0).
        seen: dict = {}
        for key, value in node.value:
            line = key.start_mark.line + 1
            name = key.value if isinstance(key, yaml.ScalarNode) else f"(key at line {line})"
            if isinstance(key, yaml.ScalarNode) and key.tag != _MERGE:
                # A key is a value too: 010 as a key is the key 8.
                _check_nodes(key, place.at(name, line), holding, checked)
                read = _key_read(key)
                # Seen before, not on another line: a flow mapping holds both on one.
                if read in seen:
                    raise ValueError(
                        f"{place.where}: {_twice(place.keys, seen[read], (line, name, read))}"
                    )
                seen[read] = (line, name, read)
            _check_nodes(value, place.at(name, line), (*holding, node), checked)
    checked.add(id(node))


def _key_read(key: yaml.ScalarNode) -> object:
    """The value the safe loader's mappings read the scalar ``key`` as: ``=``, which YAML 1.1
    tags with its ``value`` tag, as the text ``'='``; ``ConstructorError`` (a ``YAMLError``, at
    the key) for a key tagged as a collection (``!!set k``), which no mapping can hold."""
    if key.tag == _VALUE:
        return key.value
    read = yaml.constructor.SafeConstructor().construct_object(key)
    if not isinstance(read, Hashable):
        raise yaml.constructor.ConstructorError(
            "while constructing a mapping", None, "found unhashable key", key.start_mark
        )
    return read


def _twice(keys: tuple, first: tuple[int, str, object], then: tuple[int, str, object]) -> str:
    """A key below ``keys`` given twice: ``first`` and ``then`` its ``(line, text, value read)``
    (lines from 1), the values equal: the same (``yes`` and ``true``, both True) or of two
    types a mapping holds as one key (``true`` and ``1``, True and 1)."""
    (line, name, read), (again, text, read_again) = first, then
    where = f"twice on line {line}" if line == again else f"twice, at lines {line} and {again}"
    if name == text:
        written = ""
    elif repr(read) == repr(read_again):
        written = f" (as {name} and {text}, both read as {read!r})"
    else:
        written = (
            f" (as {name} and {text}, read as {read!r} and {read_again!r}, which a mapping "
            "holds as one key)"
        )
    return (
        f"{'.'.join(map(declared.key_name, (*keys, name)))} is given {where}{written}: YAML "
        "keeps the last alone; keep one"
    )


def _tag_problem(node: yaml.ScalarNode) -> str | None:
    """Why the scalar ``node``, tagged as a number (``!!int seven``, ``!!float abc``, ``!!int
    1.5``), is none, or None: the reader fails on it in Python's words alone (``could not
    convert string to float``), naming neither the file nor the key."""
    if node.tag not in (_INTEGER, _FLOAT):
        return None
    try:
        yaml.constructor.SafeConstructor().construct_object(node)
    except ValueError:
        kind = node.tag.rpartition(":")[2]
        return (
            f"{node.value} is tagged as a number ({kind}), and is none; write the number in "
            "decimal digits, or leave the tag out if text is meant"
        )
    return None


def _date_problem(node: yaml.ScalarNode) -> str | None:
    """Why the scalar ``node``, which YAML 1.1 reads as a date (``2020-02-30``: its digits
    alone make it one), is no date, or None: the reader fails on it in Python's words alone
    (``day is out of range for month``), naming neither the file nor the key."""
    if node.tag != _DATE:
        return None
    try:
        yaml.constructor.SafeConstructor().construct_yaml_timestamp(node)
    except ValueError as error:
        return f"{node.value} is read as a date, and is none ({error}); in quotes it is text"
    return None


def _number_problem(node: yaml.ScalarNode) -> str | None:
    """Why the scalar ``node`` reads as another number than its digits show, or None:
    an integer with a leading 0 (octal), a base prefix (``0x``, ``0b``), an underscore
    (dropped) or a colon (base 60), which YAML 1.1, PyYAML's and Snakemake's, reads so
    (``010`` is 8); a float with an underscore or a colon; a plain number JSON and YAML 1.2 read
    that YAML 1.1 reads as text (``1e-3``, ``1.0e3``, ``-.5``), named with the form it reads as
    that number. Quoted, any of these is text, unless tagged a number (``!!int "010"``)."""
    text = node.value
    number = _NUMBER_1_2.fullmatch(text)
    # Plain, not quoted: the C parser marks a plain scalar with the style "", the other None.
    if node.tag == _TEXT and not node.style and number:
        return (
            f"{text} is read as the text {text!r}: YAML 1.1 reads a number with an exponent "
            "only with a dot before it and a sign in it, and a sign only before a digit; "
            f"write it as {_yaml_1_1_number(number)}, or in quotes if text is meant"
        )
    # By its tag, not its quotes: a quoted number is text, but one tagged !!int reads as 8 too.
    integer = node.tag == _INTEGER and not _DECIMAL.fullmatch(text)
    if not integer and not (node.tag == _FLOAT and ("_" in text or ":" in text)):
        return None
    return (
        f"{text} is read as {read_yaml(text)!r} ({_base_reason(text)}); write the number in "
        "decimal digits, with no leading 0, underscore or colon"
    )


def _yaml_1_1_number(number: re.Match) -> str:
    """The number ``number`` (a match of ``_NUMBER_1_2``) written as YAML 1.1 reads it: a
    digit before the dot, a dot in the mantissa of an exponent, a sign in the exponent
    (``1e3`` -> ``1.0e+3``, ``-.5`` -> ``-0.5``)."""
    mantissa = number["mantissa"]
    if mantissa.startswith("."):
        mantissa = "0" + mantissa
    elif "." not in mantissa:
        mantissa += ".0"
    exponent = number["exponent"]
    if exponent is None:
        return number["sign"] + mantissa
    return f"{number['sign']}{mantissa}e{'' if exponent[0] in '+-' else '+'}{exponent}"


def _base_reason(text: str) -> str:
    """What makes YAML 1.1 read the number ``text`` in a base other than ten, or drop some of
    its characters."""
    digits = text.lstrip("+-")
    if ":" in digits:
        return "a colon makes it base 60"
    if digits[:2] in ("0x", "0X"):
        return "0x makes it hexadecimal"
    if digits[:2] in ("0b", "0B"):
        return "0b makes it binary"
    if digits.startswith("0") and "." not in digits:
        return "a leading 0 makes it octal"
    return "YAML drops the underscores"


def _yaml_error_place(error: yaml.YAMLError, text: str) -> str:
    """Where in ``text`` the YAML ``error`` is and what it is, as `` at line 2, column 1:
    found character that cannot start any token (...)``; the YAML library's own message spans
    lines and names no file. A tab, which YAML never takes as indentation, is said to be one."""
    mark = getattr(error, "problem_mark", None)
    problem = getattr(error, "problem", None) or str(error).replace("\n", " ")
    if mark is None:
        return f": {problem}"
    lines = text.splitlines()
    line = lines[mark.line] if mark.line < len(lines) else ""
    tab = (
        " (a tab: YAML indents with spaces only)"
        if line[mark.column : mark.column + 1] == "\t"
        else ""
    )
    return f" at line {mark.line + 1}, column {mark.column + 1}: {problem}{tab}"


def _merged(base: Mapping, update: Mapping) -> dict:
    merged = dict(base)
    for key, value in update.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = _merged(merged[key], value)
        else:
            merged[key] = value
    return merged


def check_config(config: Mapping) -> None:
    """Raise ``ValueError`` naming the key and its allowed values for what the schema cannot
    see: a run of no study, the time limit of an external estimator's job
    (:func:`~jointbench.running.timelimit.limit_problem`), the blind copies' translation
    (:func:`~jointbench.configuration.bounds.translation_problem`), the trial count's bound,
    protocol fields, grid keys and values, the bounds a study's own declarations do not state
    (:mod:`jointbench.configuration.bounds`), estimator names and their options (each against
    the type and range its annotation declares, see :mod:`jointbench.declared`), a study with
    no estimator, and a condition whose trials are too short for every estimator listed.

    Run on a config that passed :func:`validate_config`, before any job, so that a mistake
    stops the workflow instead of turning into failed rows or numpy errors later.
    """
    if not study_names(config):
        raise ConfigError(
            "config: studies: every study has enabled: false, so there is nothing to run; "
            "enable at least one",
            [("studies", study, "enabled") for study in config["studies"]],
        )
    jobs = config.get("jobs", {})
    # Absent, the schema's default, which the workflow's validation fills in, is the limit.
    if timelimit.KEY_PATH[-1] in jobs:
        problem = timelimit.limit_problem(jobs[timelimit.KEY_PATH[-1]])
        if problem:
            raise _refused([timelimit.KEY_PATH], problem)
    placement = config.get("blind_placement", {})
    if "translation_mm" in placement:
        problem = translation_problem(placement["translation_mm"])
        if problem:
            raise _refused([("blind_placement", "translation_mm")], problem)
    for study, settings in config["studies"].items():
        spec = get_study(study)
        where = ("studies", study)
        trials = settings["trials"]
        if not 1 <= trials <= MAX_TRIALS:
            raise _refused(
                [(*where, "trials")], f"{trials!r} is not an integer in [1, {MAX_TRIALS}]"
            )
        protocol = _protocol(spec, settings.get("protocol"), where)
        _check_grid(spec, settings["grid"], protocol, where)
        # The frames first: the study's bounds lay out a trial's frames, which must exist and fit.
        _check_estimators(spec, settings, where)
        _check_frames(spec, settings, protocol, where)
        problem = study_problem(study, settings, protocol)
        if problem:
            paths, why = problem
            raise _refused([(*where, *path) for path in paths], why)


def _refused(paths: Sequence[tuple], why: str) -> ConfigError:
    """The refusal of the config at ``paths`` (keys and list indices from the top, each a
    tuple, the text of them :func:`~jointbench.declared.keys`) for ``why``:
    ``config: studies.cmc.trials: ...``."""
    return ConfigError(f"config: {declared.keys(paths)}: {why}", paths)


def _declaration_refused(where: tuple, error: declared.DeclarationError) -> ConfigError:
    """The refusal of the values below the keys ``where`` that ``error`` is at."""
    if not error.path:
        return _refused([where], error.reason)
    return _refused([(*where, *path) for path in error.paths], error.reason)


def _protocol(spec: Study, overrides: Mapping | None, where: tuple) -> object:
    """The study's protocol from the config's overrides, or ``ConfigError`` naming the field."""
    try:
        return spec.protocol(overrides)
    except declared.DeclarationError as error:
        raise _declaration_refused((*where, "protocol"), error) from None
    except (TypeError, ValueError) as error:
        raise _refused([(*where, "protocol")], str(error)) from None


def _check_grid(spec: Study, grid: Mapping, protocol, where: tuple) -> None:
    keys = ", ".join(spec.grid_keys)
    for key in grid:
        if key not in spec.grid_keys:
            raise _refused(
                [(*where, "grid", key)], f"unknown grid key; the {spec.name} keys: {keys}"
            )
    for key in spec.grid_keys:
        if key not in grid:
            raise _refused([(*where, "grid", key)], f"missing; the {spec.name} grid needs {keys}")
        allowed = spec.grid_spec.get(key)
        for value in grid[key]:
            if allowed is not None and not allowed.accepts(value, protocol):
                # A bound the protocol sets may be the protocol's mistake: say where it is.
                by_protocol = f" (the bound studies.{spec.name}.protocol sets)"
                source = by_protocol if allowed.by_protocol else ""
                raise _refused(
                    [(*where, "grid", key)],
                    f"{value!r} is not allowed; allowed: {allowed.allowed(protocol)}{source}",
                )
        repeated = sorted({str(v) for v in grid[key] if grid[key].count(v) > 1})
        if repeated:
            raise _refused([(*where, "grid", key)], f"{', '.join(repeated)} listed more than once")


def _check_estimators(spec: Study, settings: Mapping, where: tuple) -> None:
    known = list(dict.fromkeys(m for kind in spec.kinds for m in registry.methods(kind)))
    builtin = list(settings.get("estimators", []))
    external = list(settings.get("external_estimators", []))
    if settings.get("enabled", True) and not builtin:
        if not external:
            raise _refused(
                [(*where, "estimators")],
                "empty, and no external_estimators: the study would run no estimator; list "
                f"some ({', '.join(known)}) or set enabled: false",
            )
        # Its papers' figures, tables and checks compare the built-in estimators; without one
        # they would fail after the external estimators had run.
        raise _refused(
            [(*where, "estimators")],
            f"empty: external_estimators ({', '.join(map(repr, external))}) are ranked beside "
            "the study's built-in estimators, whose comparisons its papers' figures, tables and "
            f"checks make; list at least one ({', '.join(known)})",
        )
    for name in builtin:
        if name not in known:
            raise _refused(
                [(*where, "estimators")],
                f"unknown {' or '.join(spec.kinds)} estimator {name!r}; known: "
                f"{', '.join(known)} (an estimator with a rule of its own goes under "
                "external_estimators)",
            )
    clash = [n for n in settings.get("external_estimators", []) if n in {*known, *builtin}]
    if clash:
        # Both would write results/estimates/{study}/{name}/: the files would collide.
        raise _refused(
            [(*where, "external_estimators")],
            f"{clash} have the name of a built-in estimator; rename them",
        )
    for name, options in settings.get("options", {}).items():
        if name not in builtin:
            raise _refused(
                [(*where, "options", name)],
                f"{name!r} is not listed under studies.{spec.name}.estimators; options go to "
                f"those built-in estimators: {', '.join(builtin) or 'none'}",
            )
        _check_options(spec, name, options, (*where, "options", name))


def _check_options(spec: Study, name: str, options: Mapping, where: tuple) -> None:
    """Each of ``options`` against the type its estimator's signature declares for it."""
    try:
        kind = method_kind(spec, name)
        accepted = declared.keyword_types(registry.get(kind, name), len(spec.segments_of(kind)))
    except NameError as error:
        raise _refused([where], f"the types of {name}'s options cannot be read: {error}") from None
    if accepted is None:  # it takes **options: any name, any value
        return
    for option, value in options.items():
        if option not in accepted:
            raise _refused(
                [(*where, option)],
                f"{name} takes no option {option!r}; its options: {', '.join(accepted) or 'none'}",
            )
        if accepted[option] is inspect.Parameter.empty:
            raise _refused(
                [(*where, option)],
                f"{name} does not declare what {option!r} takes, so it cannot be checked before "
                "the run: annotate the parameter (jointbench.declared)",
            )
        try:
            declared.check(value, accepted[option], (option,))
        except declared.DeclarationError as error:
            raise _declaration_refused(where, error) from None


def _check_frames(spec: Study, settings: Mapping, protocol: object, where: tuple) -> None:
    """Refuse a condition whose trials have fewer frames than any built-in estimator listed
    fits (its :class:`~jointbench.estimators.registry.Claims`): all its rows would fail; or
    whose trials hold more than :data:`MAX_CONDITION_FRAMES` frames together.

    The frames are the study's count from its protocol (:func:`trial_frames`), which a job
    holds its simulated trials to, whatever key or protocol field sets them; what a trial
    holds is its recording's where the study draws more frames than it keeps
    (:attr:`~jointbench.simulate.Study.recorded_frames`). The refusal names the grid key that
    sets a trial's frames, or the protocol fields the recording's are read from
    (:func:`_frame_source`), with their values where the study gives them (a count read from
    several fields, :attr:`~jointbench.simulate.Study.frame_values`).
    External estimators declare no minimum and are not counted.
    """
    needs = {
        name: registry.claims(method_kind(spec, name), name).min_frames
        for name in settings["estimators"]
    }
    fewest = min(needs.values(), default=0)
    frames_key = next((key for key, values in spec.grid_spec.items() if values.frames), None)
    for condition in _cells(spec, settings["grid"]):
        n_frames = trial_frames(spec, protocol, condition)
        recording, unnamed = _frame_source(spec, condition, settings.get("protocol") or {})
        culprit, note = ([("grid", frames_key)], "") if frames_key else (recording, unnamed)
        recorded = spec.recorded_frames(protocol) if spec.recorded_frames else n_frames
        # The protocol's values go with the count they set: the recording's, or the trial's
        # where no grid key sets that.
        values = _frame_values(spec, condition, protocol)
        held = f"{n_frames} frame(s)" + ("" if frames_key else values)
        if max(n_frames, recorded) * settings["trials"] > MAX_CONDITION_FRAMES:
            if recorded > n_frames:
                culprit, note = recording, unnamed
                held = f"{n_frames} frame(s) of recordings of {recorded} frame(s){values}"
            raise _refused(
                [(*where, *path) for path in culprit],
                f"condition {condition_id(condition)} has trials of {held}, "
                f"{settings['trials']} trials of which hold more than {MAX_CONDITION_FRAMES} "
                f"frames, what one job can hold{note}",
            )
        if n_frames < fewest:
            listed = ", ".join(f"{name} {n}" for name, n in needs.items())
            raise _refused(
                [(*where, *path) for path in culprit],
                f"condition {condition_id(condition)} has trials of {held}, fewer than any "
                f"listed estimator fits (at least: {listed}){note}",
            )


def _frame_values(spec: Study, condition: Mapping, protocol: object) -> str:
    """`` (from field value, ...)``: the values of the protocol fields ``condition``'s
    recordings' frames are read from, where the study gives them
    (:attr:`~jointbench.simulate.Study.frame_values`); else nothing."""
    if spec.frame_values is None:
        return ""
    return f" (from {field_values(spec.frame_values(condition, protocol))})"


def _frame_source(spec: Study, condition: Mapping, overrides: Mapping) -> tuple[list, str]:
    """``(paths, note)``: the paths of keys below ``studies.<study>`` of the protocol fields
    that set the frames of ``condition``'s recordings
    (:attr:`~jointbench.simulate.Study.frame_keys`) and no note; for a study that does not
    declare them, its ``protocol`` and a note saying why no field is named. ``TypeError``
    naming the study where its ``frame_keys`` gives no list of one or more paths, each a
    tuple of one or more keys (a text, as before they were paths; an iterator, which checking
    would use up)."""
    if spec.frame_keys is None:
        return [("protocol",)], (
            f" (study {spec.name!r} declares no frame_keys: which of its protocol fields its "
            "frame_count reads, only the study can say)"
        )
    paths = spec.frame_keys(condition, overrides)
    # A text is a sequence too, of characters, none of them a tuple.
    if (
        not isinstance(paths, Sequence)
        or not paths
        or not all(isinstance(path, tuple) and path for path in paths)
    ):
        raise TypeError(
            f"study {spec.name!r}: its frame_keys gave {paths!r} for condition "
            f"{condition_id(condition)}, not a list of paths of keys, each a tuple "
            '([("protocol", "n_frames")])'
        )
    return list(paths), ""


def trial_frames(spec: Study, protocol: object, condition: Mapping) -> int:
    """The frames of a trial of ``spec``'s ``condition`` under ``protocol``: the study's count
    from its protocol (:attr:`~jointbench.simulate.Study.frame_count`), which every study
    declares, so that none is simulated to be counted. ``TypeError`` naming the study where
    the count is not a whole number of 0 or more: a mistake in the study, which no config
    value can make (a protocol's own fields are bounded by their declarations)."""
    n_frames = spec.frame_count(condition, protocol)
    if isinstance(n_frames, bool) or not isinstance(n_frames, numbers.Integral) or n_frames < 0:
        raise TypeError(
            f"study {spec.name!r}: its frame_count gave {n_frames!r} for condition "
            f"{condition_id(condition)}, not a count of frames (a whole number, 0 or more)"
        )
    return int(n_frames)


def study_names(config: Mapping) -> list[str]:
    """Studies switched on in the config, in the study registry's order, which a run opens its
    config in (:func:`open_config`): the package's studies in the order of their simulator
    modules' names, then those of the extensions in the order of their files' names
    (:func:`~jointbench.configuration.extensions.in_load_order`). It orders the report's sections
    and the comparison's rows; the order in which the config lists the studies, or the
    extensions, means nothing."""
    return [name for name, study in config["studies"].items() if study.get("enabled", True)]


def verdict_seeds(config: Mapping) -> int:
    """K, the base seeds ``snakemake verdicts`` judges every published value and claim over
    (the config's ``verdicts.seeds``, 1 where it is not set)."""
    return int(config.get("verdicts", {}).get("seeds", 1))


def conditions(config: Mapping, study: str) -> list[dict[str, object]]:
    """Every cell of a study's grid, as dicts in the study's key order."""
    return _cells(get_study(study), config["studies"][study]["grid"])


def _cells(spec: Study, grid: Mapping[str, list]) -> list[dict[str, object]]:
    missing = [key for key in spec.grid_keys if key not in grid]
    if missing:
        raise ValueError(f"config: study {spec.name!r} grid lacks {missing}")
    return [
        dict(zip(spec.grid_keys, values, strict=True))
        for values in itertools.product(*(grid[k] for k in spec.grid_keys))
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


def external_kind(name: str, kind: object, before: str | None) -> str:
    """``kind``, the kind of estimates the rule file of the external estimator ``name``
    declares it writes (``center``, ``axis`` or ``joint_center``: the estimate columns of each
    kind); ``ValueError`` naming ``name`` for any other, or where it was declared ``before``
    as another kind (by another rule file): which would be its files' kind is not known."""
    if not isinstance(kind, str) or kind not in KINDS:
        raise ValueError(
            f"external estimator {name!r}: kind={kind!r} is no kind of estimates; the kinds: "
            f"{', '.join(KINDS)}"
        )
    if before not in (None, kind):
        raise ValueError(
            f"external estimator {name!r} is declared twice, writing {before} estimates and "
            f"{kind} estimates; one estimator writes one kind"
        )
    return kind


def check_external_kind(study: str, name: str, kind: str | None) -> None:
    """Refuse, naming the study, the estimator and both kinds, the external estimator ``name``
    listed by ``study`` whose rule file declares estimates of ``kind`` (:func:`external_kind`),
    another kind than the study scores its external estimators' files as
    (:attr:`~jointbench.simulate.Study.kind`): a centre's rule listed by the hinge study would
    run, then fail when its files are collected, and by the hip study be scored as a joint
    centre from markers it did not read as one. A rule file that declares no kind is refused
    too, saying how to declare it: which kind it writes only its writer can say."""
    spec = get_study(study)
    where = f"config: studies.{study}.external_estimators: {name!r}"
    at = [("studies", study, "external_estimators")]
    if kind is None:
        raise ConfigError(
            f"{where}: its rule file declares no kind of estimates; if it writes {spec.kind} "
            f"estimates, the kind study {study} scores, add "
            f'external_estimator("{name}", kind="{spec.kind}") to it (README, "Any language: '
            'one rule")',
            at,
        )
    if kind != spec.kind:
        alike = [s for s in registered_studies() if get_study(s).kind == kind]
        raise ConfigError(
            f"{where} writes {kind} estimates (as its rule file declares), but study {study} "
            f"scores {spec.kind} estimates: its files would fail as they are collected, or be "
            f"scored as what they are not; list it under a study of {kind} estimates "
            f"({', '.join(alike) or 'none is registered'}), or write a rule of {spec.kind} "
            f"estimates for {study}",
            at,
        )
