"""The study configuration: loading, validation, the condition grid and its file names."""

from __future__ import annotations

import inspect
import itertools
import numbers
from collections.abc import Mapping, Sequence
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
from jointbench.simulate import Study

__all__ = [
    "MAX_TRIALS",
    "check_config",
    "check_schema",
    "condition_id",
    "conditions",
    "estimator_names",
    "load_config",
    "open_config",
    "ordered_settings",
    "parse_condition_id",
    "read_config_file",
    "read_configs",
    "read_yaml",
    "study_names",
    "validate_against",
    "validate_config",
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


def read_yaml(text: str) -> object:
    """A YAML document with the safe loader, in C when PyYAML has it (10x faster than Python's
    on the published-values files, which every render job reads)."""
    return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


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
        raise ValueError(f"{what} error at {where}: {error.message}") from None


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
    grid to the schema, but the mistake is its name. With ``extensions`` listed, a study may be
    theirs, and none is imported from a config that fails the schema: the schema's error is
    given, saying which studies are not built in. ``ValueError`` in one line naming the key.

    The workflow runs it before Snakemake's own validation, whose error leads with a dump of
    the schema; :func:`open_config` runs it first."""
    studies = config.get("studies")
    if not isinstance(studies, Mapping):
        validate_against(config, SCHEMA_PATH, "config")
        return
    if not config.get("extensions"):
        _check_studies_registered(config)
        validate_against(config, SCHEMA_PATH, "config")
        return
    try:
        validate_against(config, SCHEMA_PATH, "config")
    except ValueError as error:
        unknown = _unknown_studies(config)
        if not unknown:
            raise
        raise ValueError(
            f"{error} ({', '.join(map(repr, unknown))} is not a built-in study: built in are "
            f"{', '.join(registered_studies())}; another must come from the extensions)"
        ) from None


def _unknown_studies(config: Mapping) -> list[str]:
    return sorted(set(config["studies"]) - set(registered_studies()))


def _check_studies_registered(config: Mapping) -> None:
    """Raise ``ValueError`` naming the studies of ``config`` that no module registered."""
    unknown = _unknown_studies(config)
    if unknown:
        raise ValueError(
            f"config error at studies: unknown studies {unknown}; registered studies are "
            f"{', '.join(registered_studies())} (a study outside the package is added by listing "
            "its module under extensions)"
        )


def load_config(path: str | Path) -> dict:
    """A YAML config opened as a run opens it (:func:`open_config`)."""
    return dict(open_config(read_configs([path])))


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
    load_extensions(config, base)
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
        where = f"config error at sensitivity.named.{name} ({path})"
        document = read_config_file(Path(base) / path, where)
        merged = _merged(config, document)
        try:
            validate_against(merged, SCHEMA_PATH, "config")
            check_config(merged)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
        overlays[name] = document
    return overlays


def read_configs(paths: Sequence[str | Path]) -> dict:
    """The config of YAML files read in order, each updating the ones before as Snakemake's
    ``--configfile`` does: a mapping merged key by key, any other value replaced."""
    config: dict = {}
    for path in paths:
        config = _merged(config, read_config_file(Path(path), f"config file {path}"))
    return config


def read_config_file(path: Path, where: str) -> Mapping:
    """The mapping of config keys to values the YAML file ``path`` holds, or ``ValueError``
    in one line beginning with ``where`` (the file, or the key naming it): no such file, not
    YAML (where in the file, and why), or no mapping. An empty file, or one of comments alone,
    is refused as Snakemake's ``--configfile`` refuses it: it changes nothing, which is not
    what its writer meant."""
    if not path.is_file():
        raise ValueError(f"{where}: no such file")
    text = path.read_text()
    try:
        document = read_yaml(text)
    except yaml.YAMLError as error:
        raise ValueError(f"{where}: not valid YAML{_yaml_error_place(error, text)}") from None
    if document is None:
        raise ValueError(
            f"{where}: empty: it holds no keys (a config file sets the keys it changes)"
        )
    if not isinstance(document, Mapping):
        raise ValueError(f"{where}: not a mapping of config keys to values")
    return document


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
    see: a run of no study, the blind copies' translation
    (:func:`~jointbench.configuration.bounds.translation_problem`), the trial count's bound,
    protocol fields, grid keys and values, the bounds a study's own declarations do not state
    (:mod:`jointbench.configuration.bounds`), estimator names and their options (each against
    the type and range its annotation declares, see :mod:`jointbench.declared`), a study with
    no estimator, and a condition whose trials are too short for every estimator listed.

    Run on a config that passed :func:`validate_config`, before any job, so that a mistake
    stops the workflow instead of turning into failed rows or numpy errors later.
    """
    if not study_names(config):
        raise ValueError(
            "config: studies: every study has enabled: false, so there is nothing to run; "
            "enable at least one"
        )
    placement = config.get("blind_placement", {})
    if "translation_mm" in placement:
        problem = translation_problem(placement["translation_mm"])
        if problem:
            raise ValueError(f"config: blind_placement.translation_mm: {problem}")
    for study, settings in config["studies"].items():
        spec = get_study(study)
        where = f"config: studies.{study}"
        trials = settings["trials"]
        if not 1 <= trials <= MAX_TRIALS:
            raise ValueError(f"{where}.trials: {trials!r} is not an integer in [1, {MAX_TRIALS}]")
        protocol = _protocol(spec, settings.get("protocol"), where)
        _check_grid(spec, settings["grid"], protocol, where)
        # The frames first: the study's bounds lay out a trial's frames, which must exist and fit.
        _check_estimators(spec, settings, where)
        _check_frames(spec, settings, protocol, where)
        problem = study_problem(study, settings, protocol)
        if problem:
            raise ValueError(f"{where}.{problem[0]}: {problem[1]}")


def _protocol(spec: Study, overrides: Mapping | None, where: str) -> object:
    """The study's protocol from the config's overrides, or ``ValueError`` naming the field."""
    try:
        return spec.protocol(overrides)
    except declared.DeclarationError as error:
        raise ValueError(f"{where}.protocol.{error}") from None
    except (TypeError, ValueError) as error:
        raise ValueError(f"{where}.protocol: {error}") from None


def _check_grid(spec: Study, grid: Mapping, protocol, where: str) -> None:
    keys = ", ".join(spec.grid_keys)
    for key in grid:
        if key not in spec.grid_keys:
            raise ValueError(f"{where}.grid.{key}: unknown grid key; the {spec.name} keys: {keys}")
    for key in spec.grid_keys:
        if key not in grid:
            raise ValueError(f"{where}.grid.{key}: missing; the {spec.name} grid needs {keys}")
        allowed = spec.grid_spec.get(key)
        for value in grid[key]:
            if allowed is not None and not allowed.accepts(value, protocol):
                # A bound the protocol sets may be the protocol's mistake: say where it is.
                by_protocol = f" (the bound studies.{spec.name}.protocol sets)"
                source = by_protocol if allowed.by_protocol else ""
                raise ValueError(
                    f"{where}.grid.{key}: {value!r} is not allowed; "
                    f"allowed: {allowed.allowed(protocol)}{source}"
                )
        repeated = sorted({str(v) for v in grid[key] if grid[key].count(v) > 1})
        if repeated:
            raise ValueError(f"{where}.grid.{key}: {', '.join(repeated)} listed more than once")


def _check_estimators(spec: Study, settings: Mapping, where: str) -> None:
    known = list(dict.fromkeys(m for kind in spec.kinds for m in registry.methods(kind)))
    builtin = list(settings.get("estimators", []))
    external = list(settings.get("external_estimators", []))
    if settings.get("enabled", True) and not builtin:
        if not external:
            raise ValueError(
                f"{where}.estimators: empty, and no external_estimators: the study would run no "
                f"estimator; list some ({', '.join(known)}) or set enabled: false"
            )
        # Its papers' figures, tables and checks compare the built-in estimators; without one
        # they would fail after the external estimators had run.
        raise ValueError(
            f"{where}.estimators: empty: external_estimators ({', '.join(map(repr, external))}) "
            "are ranked beside the study's built-in estimators, whose comparisons its papers' "
            f"figures, tables and checks make; list at least one ({', '.join(known)})"
        )
    for name in builtin:
        if name not in known:
            raise ValueError(
                f"{where}.estimators: unknown {' or '.join(spec.kinds)} estimator {name!r}; known: "
                f"{', '.join(known)} (an estimator with a rule of its own goes under "
                "external_estimators)"
            )
    clash = [n for n in settings.get("external_estimators", []) if n in {*known, *builtin}]
    if clash:
        # Both would write results/estimates/{study}/{name}/: the files would collide.
        raise ValueError(
            f"{where}.external_estimators: {clash} have the name of a built-in estimator; "
            "rename them"
        )
    for name, options in settings.get("options", {}).items():
        if name not in builtin:
            raise ValueError(
                f"{where}.options.{name}: {name!r} is not listed under "
                f"studies.{spec.name}.estimators; options go to those built-in estimators: "
                f"{', '.join(builtin) or 'none'}"
            )
        _check_options(spec, name, options, f"{where}.options.{name}")


def _check_options(spec: Study, name: str, options: Mapping, where: str) -> None:
    """Each of ``options`` against the type its estimator's signature declares for it."""
    try:
        kind = method_kind(spec, name)
        accepted = declared.keyword_types(registry.get(kind, name), len(spec.segments_of(kind)))
    except NameError as error:
        raise ValueError(
            f"{where}: the types of {name}'s options cannot be read: {error}"
        ) from None
    if accepted is None:  # it takes **options: any name, any value
        return
    for option, value in options.items():
        if option not in accepted:
            raise ValueError(
                f"{where}.{option}: {name} takes no option {option!r}; "
                f"its options: {', '.join(accepted) or 'none'}"
            )
        if accepted[option] is inspect.Parameter.empty:
            raise ValueError(
                f"{where}.{option}: {name} does not declare what {option!r} takes, so it cannot "
                "be checked before the run: annotate the parameter (jointbench.declared)"
            )
        try:
            declared.check(value, accepted[option], (option,))
        except declared.DeclarationError as error:
            raise ValueError(f"{where}.{error}") from None


def _check_frames(spec: Study, settings: Mapping, protocol: object, where: str) -> None:
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
        culprit, note = (f"grid.{frames_key}", "") if frames_key else (recording, unnamed)
        recorded = spec.recorded_frames(protocol) if spec.recorded_frames else n_frames
        # The protocol's values go with the count they set: the recording's, or the trial's
        # where no grid key sets that.
        values = _frame_values(spec, condition, protocol)
        held = f"{n_frames} frame(s)" + ("" if frames_key else values)
        if max(n_frames, recorded) * settings["trials"] > MAX_CONDITION_FRAMES:
            if recorded > n_frames:
                culprit, note = recording, unnamed
                held = f"{n_frames} frame(s) of recordings of {recorded} frame(s){values}"
            raise ValueError(
                f"{where}.{culprit}: condition {condition_id(condition)} has trials of {held}, "
                f"{settings['trials']} trials of which hold more than {MAX_CONDITION_FRAMES} "
                f"frames, what one job can hold{note}"
            )
        if n_frames < fewest:
            listed = ", ".join(f"{name} {n}" for name, n in needs.items())
            raise ValueError(
                f"{where}.{culprit}: condition {condition_id(condition)} has trials of "
                f"{held}, fewer than any listed estimator fits (at least: {listed}){note}"
            )


def _frame_values(spec: Study, condition: Mapping, protocol: object) -> str:
    """`` (from field value, ...)``: the values of the protocol fields ``condition``'s
    recordings' frames are read from, where the study gives them
    (:attr:`~jointbench.simulate.Study.frame_values`); else nothing."""
    if spec.frame_values is None:
        return ""
    return f" (from {field_values(spec.frame_values(condition, protocol))})"


def _frame_source(spec: Study, condition: Mapping, overrides: Mapping) -> tuple[str, str]:
    """``(keys, note)``: the keys below ``studies.<study>`` of the protocol fields that set the
    frames of ``condition``'s recordings (:attr:`~jointbench.simulate.Study.frame_keys`) and
    no note; for a study that does not declare them, its ``protocol`` and a note saying why
    no field is named."""
    if spec.frame_keys is not None:
        return spec.frame_keys(condition, overrides), ""
    return "protocol", (
        f" (study {spec.name!r} declares no frame_keys: which of its protocol fields its "
        "frame_count reads, only the study can say)"
    )


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
