# Helpers shared by the rules: config checks, the study and paper registries, file lists.
import base64
import contextlib
import functools
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from snakemake.io import WILDCARD_REGEX, apply_wildcards
from snakemake.logging import logger
from snakemake.utils import validate

from jointbench import invocation, pipeline, report as jb_report
from jointbench import jobs as jb_jobs
from jointbench.figures.common import study_title
from jointbench.fingerprint import (
    OnePass,
    check_bytecode_by_content,
    code_fingerprint,
    compiler_version,
    data_names,
    dependency_versions,
    source_digests,
)
from jointbench.running import run as jb_run
from jointbench.running import landlock, timelimit
from jointbench.papers import get_paper, paper_names, papers_of_study
from jointbench.configuration import config as jb_config

validate(config, str(jb_config.SCHEMA_PATH))
# Extensions loaded, then grid values, estimator names and options checked: a mistake stops the
# run here, naming the key and the config files that set it (the command line opens a run's
# config the same way).
with jb_config.sources_named(CONFIG_SOURCES):
    jb_config.open_config(config)

# Advice a job prints (the --forcerun for an unreadable file) repeats this run's options: its
# --configfile and --config, --directory, --profile.
invocation.record(sys.argv[1:])

STUDIES = jb_config.study_names(config)
# The interpreter running this workflow, for external estimators' shell commands.
PYTHON = sys.executable


def studies_listing(estimator):
    """The studies of this run that list ``estimator`` under ``external_estimators``: an
    external rule written for every study runs for these and ignores the others."""
    return [
        study
        for study in STUDIES
        if estimator in jb_config.estimator_names(config, study, source="external")
    ]


# Every job of an external estimator runs under one time limit (limit_user_jobs): the shell it
# is run by (jointbench/running/limited/bash) reads it, and the interpreter it runs on, here.
TIME_LIMIT_S = timelimit.configured_limit(config)
os.environ[timelimit.LIMIT_VARIABLE] = repr(TIME_LIMIT_S)
os.environ[timelimit.PYTHON_VARIABLE] = PYTHON


# Every external estimator of this run's studies.
EXTERNAL_ESTIMATORS = sorted(
    {
        n
        for s in STUDIES
        for n in jb_config.estimator_names(config, s, source="external")
    }
)


# The kind of estimates each external estimator's rule file declares (external_estimator), by
# name: held to the kind of each study of the run that lists it, before any job.
EXTERNAL_KINDS = {}


def external_estimator(name, kind):
    """Declare, in the rule file of the external estimator ``name``, the kind of the estimates
    its rule writes, ``center``, ``axis`` or ``joint_center`` (README, "The estimates file").
    A study of another kind that lists it stops the run before any job."""
    EXTERNAL_KINDS[name] = jb_config.external_kind(name, kind, EXTERNAL_KINDS.get(name))


def include_user_rules(folder):
    """Include every rule file of ``folder``, the user's, and return the names of the rules
    they define (those of a file they include too, whatever its folder). The names of the
    package's rules, defined before, are held in this call alone: a rule file's code runs in
    the workflow's namespace, where it could change or rebind a set of names kept there.
    """
    load, rules = workflow.include, workflow.rules
    package = frozenset(r.name for r in rules)
    for path in sorted(Path(folder).glob("*.smk")):
        load(path)
    return frozenset(r.name for r in rules) - package


def check_external_rules(user_rules):
    """Stop, naming the study and the estimator, when no rule writes the estimates of an
    external estimator of this run, as parquet or as the CSV that estimates_from_csv converts
    (a misspelt name, a rule file not yet written), not at a missing CSV later; when its rule
    file declares another kind of estimates than the study's, or none (see external_estimator
    and jb_config.check_external_kind); when a rule of the user's (``user_rules``, by name)
    can write a file of the benchmark's (see _check_user_outputs) or a file outside results/
    (see _check_user_folders); when two rules
    write its estimates (see _refuse_rival_writers); and when its rule reads a file of
    results/ other than the blind copies (see _check_blind). First, when a wildcard's
    constraint in a file a rule of the user's writes is no regular expression (see
    _check_user_patterns)."""
    users = [r for r in workflow.rules if r.name in user_rules]
    _check_user_patterns(users)
    _check_user_outputs(users, _package_rules(user_rules))
    _check_user_folders(users)
    writers = [r for r in workflow.rules if r.name != "estimates_from_csv"]
    for study in STUDIES:
        for name in jb_config.estimator_names(config, study, source="external"):
            parquets = estimates_files(study, [name])
            files = [
                f for p in parquets for f in (p, p.removesuffix(".parquet") + ".csv")
            ]
            producers = [w for w in writers if any(_produces(w, f) for f in files)]
            if not producers:
                raise jb_config.ConfigError(
                    f"config: studies.{study}.external_estimators: no rule writes the "
                    f"estimates of {name!r} ({files[0]} or .csv); its rule goes in "
                    "workflow/rules/estimators/ (README, 'Adding an estimator')",
                    [("studies", study, "external_estimators")],
                )
            _refuse_rival_writers(study, name, files, producers)
            for producer in producers:
                _check_blind(producer, name, files, users)
            jb_config.check_external_kind(study, name, EXTERNAL_KINDS.get(name))


def _check_user_patterns(users):
    """Stop, naming the rule and the file, where a file a rule of ``users`` (the user's) writes
    has a wildcard whose constraint is no regular expression, or is given again where the
    wildcard recurs: every check below matches paths with them, and would stop on the bare
    error of the regular expression, naming neither."""
    for user in users:
        for product in user.products():
            try:
                product.regex()
            except (re.error, ValueError) as error:
                raise ValueError(
                    f"rule {user.name} writes {product}, whose wildcard constraint is no "
                    f"regular expression ({error})"
                ) from None


def _produces(rule, path):
    """Whether ``rule`` writes ``path``, as Rule.is_producer judges it, found in an index of
    its products (:func:`_products`): a rule writing every condition's file in one job has as
    many outputs as conditions, and asking each of them about each file made the plan grow as
    their square."""
    literal, patterns = _products(rule.name)
    # A pattern's regular expression ends in $, which also takes a final newline.
    return path.removesuffix("\n") in literal or any(p.match(path) for p in patterns)


@functools.cache
def _products(name):
    """The products of rule ``name`` (outputs, logs, benchmark file, as is_producer reads
    them), ``(literal, patterns)``: the paths without a wildcard, and those with one. Asked only
    once every rule is read (check_external_rules runs last)."""
    products = list(workflow.get_rule(name).products())
    literal = frozenset(str(p) for p in products if not p.contains_wildcard())
    return literal, [p for p in products if p.contains_wildcard()]


def _package_rules(user_rules):
    """The rules of the benchmark's, all but those of the user's (``user_rules``, by name)
    and estimates_from_csv, which writes an external estimator's estimates (converted from its
    CSV), which its rule may write too."""
    return [
        r
        for r in workflow.rules
        if r.name not in user_rules and r.name != "estimates_from_csv"
    ]


def _refuse_rival_writers(study, name, files, producers):
    """Stop when two of the rules ``producers`` write one of ``files``, the estimates of the
    external estimator ``name`` in ``study``, naming them and the file: which one runs would be
    decided by a rule order, not by the estimator's name, and the answers of one would be
    ranked under the other's."""
    for path in files:
        rivals = sorted(p.name for p in producers if _produces(p, path))
        if len(rivals) > 1:
            raise jb_config.ConfigError(
                f"rules {' and '.join(rivals)} both write the estimates of {name!r} in study "
                f"{study} ({path}): an estimator's estimates are written by its own rule "
                "alone (README, 'Adding an estimator')",
                [("studies", study, "external_estimators")],
            )


# The only files the benchmark writes under results/ that a rule of an external estimator may
# read: the blind copies and their CSV form. Anything else there was made from the truth, from
# the unplaced datasets or from scores (an estimates file holds each answer and its error, from
# which the truth follows), so it is refused by default rather than listed as forbidden.
READABLE = ("results/blind/", "results/interchange/")

# Why a refused file may not be read, by folder; any other folder of results/ gets the default.
UNSEEN = {
    "results/datasets/": "the truth the benchmark scores with",
    "results/placements/": (
        "the placement of each trial of a blind copy, which the benchmark maps an external "
        "estimator's answers back with"
    ),
}
_UNSEEN_DEFAULT = (
    "what the benchmark made from the truth, the unplaced datasets or the scores (an "
    "estimates file holds each answer and its error)"
)


def _unreadable(path, users):
    """Why the rules of an external estimator may not read ``path`` (as judged, see _judged),
    or None; a folder holding results/, or a file under results/ that is neither a blind copy
    nor written by one of ``users``, the rules of the user's (which are checked in turn; none
    can write a file of the benchmark's), whether their output is spelt relative to the
    working directory or absolute."""
    if _holds_results(path):
        return "results/, and so the truth and every file the benchmark made from it"
    if not path.startswith("results/"):
        return None
    if path.startswith(READABLE):
        return None
    spellings = (path, os.path.abspath(path))
    if any(_produces(other, f) for other in users for f in spellings):
        return None
    return next(
        (held for folder, held in UNSEEN.items() if path.startswith(folder)),
        _UNSEEN_DEFAULT,
    )


def _holds_results(path):
    """Whether ``path`` is results/ or a folder holding it (``.``, the repository)."""
    real = Path(os.path.realpath(path))
    folders = (os.path.abspath("results"), os.path.realpath("results"))
    return any(Path(folder).is_relative_to(real) for folder in folders)


def _linked(path):
    """What ``path`` (as matched) holds by way of the first symbolic link among its existing
    folders and file below results/ (results/ itself may be a link to a larger disk), or None:
    a link there can make a blind path open the truth, or lead out of results/."""
    if not path.startswith("results/"):
        return None
    parts = Path(path).parts
    for end in range(2, len(parts) + 1):
        here = Path(*parts[:end])
        if here.is_symlink():
            return f"whatever the symbolic link {here.as_posix()} leads to"
    return None


def _refusal(path, users):
    """``(shown, held)``: ``path`` (as matched) as a refusal names it, with its real path where
    that differs, and what it holds that the rules of an external estimator may not read (see
    _linked, _unreadable); or None when they may read it."""
    link = _linked(path)
    if link is not None:
        return path, link
    real = _judged(path)
    held = _unreadable(real, users)
    if held is None:
        return None
    return (path if real == path else f"{path} (its real path {real})"), held


def _check_blind(producer, name, files, everyone, via=(), seen=frozenset()):
    """Stop when ``producer``, the rule of external estimator ``name`` or a rule of its own
    upstream (``via``: the rules it feeds, down to the estimator's), reads a file under
    results/ other than a blind copy (:data:`READABLE`) that no rule of the user's
    (``everyone``) writes, a folder holding results/, or any file there by way of a symbolic
    link below results/, in a job writing one of ``files``: each input is judged by its real
    path, however it is spelt, and read as that job's, input functions called with the job's
    wildcards. A rule of the user's upstream (the estimator's own rule too, in another job) is
    followed in turn, found by the path as written (as Snakemake finds it), as normalised and
    by its real path, so that none can hand the estimator what it read from the truth;
    ``seen`` holds the jobs already followed, as (rule, wildcards): the files a job writes share
    its inputs, which are judged once (a rule writing every condition's file in one job would
    otherwise have its inputs judged once per condition, a plan growing as their square).
    """
    for file in (f for f in files if _produces(producer, f)):
        wildcards, job = _job(producer, file)
        if job in seen:
            continue
        seen = seen | {job}
        raw = [str(f) for f in producer.expand_input(wildcards)[0]]
        spelt = [_as_matched(f) for f in raw]
        refused = [r for r in (_refusal(f, everyone) for f in spelt) if r is not None]
        if refused:
            chain = "".join(f", which feeds rule {rule}" for rule in via)
            file, held = refused[0]
            raise ValueError(
                f"rule {producer.name}{chain} (external estimator {name!r}) reads {file}, "
                f"which holds {held}: an external estimator reads "
                "the blind file results/blind/{study}/{condition}.parquet, or the markers CSV "
                "results/interchange/{study}/{condition}.csv (README, 'Adding an estimator')"
            )
        read = list(dict.fromkeys([*raw, *spelt, *map(_judged, spelt)]))
        for upstream in everyone:
            made = [f for f in read if _produces(upstream, f)]
            if made:
                _check_blind(
                    upstream, name, made, everyone, (producer.name, *via), seen
                )


# Where only the package's rules write: the blind copies and their CSV form, which an external
# estimator trusts.
BENCHMARK_ONLY = ("results/blind/", "results/interchange/")


def _job(producer, file):
    """The wildcards (a dict) of the job of rule ``producer`` writing ``file``, and that job
    as the name of its rule and its wildcards, hashable; the files a job writes share its
    inputs."""
    wildcards = dict(producer.get_wildcards(file))
    return wildcards, (producer.name, tuple(sorted(wildcards.items())))


def _check_user_outputs(users, package):
    """Stop when one of the rules ``users`` can write a file under BENCHMARK_ONLY or a file
    one of ``package`` can write, naming both. Whichever Snakemake chose to run, a file the
    user's rule claims would pass for the user's own, readable, or replace the benchmark's.
    A wildcard is taken to match anything unless it lists its names, so no overlap is missed.
    """
    theirs = _WrittenIndex(package)
    for user in users:
        for written in _written(user):
            mine = _patterns_of(written)
            inside = [
                f for f in BENCHMARK_ONLY if _overlap(mine, _patterns_of(f"{f}{{x}}"))
            ]
            held = next(iter(inside), None)
            if held is not None:
                raise ValueError(
                    f"rule {user.name} writes {_shown(written)}, under {held}"
                    ": only the benchmark writes there, and an external estimator reads "
                    "what it writes there as blind (README, 'Adding an estimator')"
                )
            overlapping = theirs.first_overlap(mine)
            if overlapping is not None:
                other, path = overlapping
                _refuse_a_builtins_name(user, written, mine, other)
                raise ValueError(
                    f"rule {user.name} writes {_shown(written)}, which rule "
                    f"{other.name} of the benchmark writes ({_shown(path)})"
                    ": a rule of yours writes files of its own, in a folder of its own"
                )


class _WrittenIndex:
    """The files the rules ``package`` write (:func:`_written`), as patterns, indexed so that a
    pattern without a wildcard is looked up, not compared with each: a rule writing every
    condition's file in one job lists as many files as conditions, and comparing each file of
    the user's rules with each of the benchmark's made the plan grow as their square."""

    def __init__(self, package):
        self.entries = [(other, f) for other in package for f in _written(other)]
        self.literal = {}  # pattern without a wildcard -> index of its first entry
        self.wild = []  # (index, pattern) of the patterns with one
        for index, (_, path) in enumerate(self.entries):
            for pattern in _patterns_of(path):
                if _WILDCARD in pattern:
                    self.wild.append((index, pattern))
                else:
                    self.literal.setdefault(pattern, index)

    def first_overlap(self, mine):
        """``(rule, path)`` of the first entry some path matching ``mine`` (patterns, as
        :func:`_patterns_of` gives) matches too, in the rules' order, or None."""
        found = [index for pattern in mine for index in self._overlapping(pattern)]
        return self.entries[min(found)] if found else None

    def _overlapping(self, pattern):
        if _WILDCARD in pattern:
            candidates = [*((i, p) for p, i in self.literal.items()), *self.wild]
        else:
            exact = self.literal.get(pattern)
            candidates = [*([] if exact is None else [(exact, pattern)]), *self.wild]
        return [
            index
            for index, theirs in candidates
            if _may_meet(pattern, theirs) and _meet(pattern, theirs)
        ]


def _refuse_a_builtins_name(user, written, mine, other):
    """Stop, naming the estimator, when ``written`` (as patterns ``mine``), a file the rule
    ``user`` writes and the rule ``other`` of the benchmark writes too, is an estimates file of
    a built-in estimator this run lists: the rule file's estimator has the built-in's name,
    whether or not a study lists it, which the user fixes by renaming one of them."""
    for study in STUDIES:
        for name in jb_config.estimator_names(config, study, source="builtin"):
            files = estimates_files(study, [name])
            if any(_overlap(mine, _patterns_of(_judged(f))) for f in files):
                raise jb_config.ConfigError(
                    f"rule {user.name} writes the estimates of {name!r} in study {study} "
                    f"({_shown(written)}), an estimator studies.{study}.estimators lists as "
                    f"built in, run by rule {other.name}"
                    # Apart: Snakemake's linter reads "rule" and a colon on one line as a rule.
                    ": a built-in estimator and a rule file's take different names (README, "
                    "'Adding an estimator')",
                    [("studies", study, "estimators")],
                )


def _check_user_folders(users):
    """Stop when one of the rules ``users`` can write a file outside RESULTS (see
    _refuse_outside). Checked after _check_user_outputs, whose message is the more telling for
    a file both refuse."""
    for user in users:
        _refuse_outside(user, _declared(user))


def _refuse_outside(producer, files):
    """Stop when one of ``files``, ``(kind, path)`` of the files ``producer`` (a rule of the
    user's) writes, as patterns or as one job's paths, can lie outside RESULTS, judged by its
    real path (``..``, an absolute path, a symbolic link below results/), naming the rule, its
    rule file and the path as written and real. A job of the benchmark's, or the next run,
    reads what lies there (the configuration, the package's code and workflow) as the
    benchmark's own."""
    for kind, written in files:
        real = _judged(written)
        if not any(p[: len(RESULTS)] != tuple(RESULTS) for p in _patterns_of(real)):
            continue
        shown = _shown(written)
        if _shown(real) != shown:
            shown = f"{shown} (its real path {_shown(real)})"
        raise ValueError(
            f"rule {producer.name} ({_as_matched(str(producer.snakefile))}) writes its {kind} "
            f"{shown}, outside {RESULTS}: a rule of yours writes its files under "
            f"{RESULTS}, in a folder of its own (README, 'Adding an estimator')"
        )


def _kept_in_results(producer, parameter):
    """``parameter``, a parameter function of ``producer`` (a rule of the user's) taking the
    wildcards, first stopping when a file of the job lies outside RESULTS (see
    _refuse_outside): a wildcard's value may climb out of results/ (``results/mine/{x}.yaml``
    asked for as ``results/mine/../../config/x.yaml``), which the patterns checked at load do
    not show. Snakemake evaluates every job's parameters as it plans the jobs, before any
    runs."""

    def checked(wildcards):
        values = dict(wildcards.items())
        files = [(kind, apply_wildcards(f, values)) for kind, f in _declared(producer)]
        _refuse_outside(producer, files)
        return parameter(wildcards)

    return checked


def _declared(producer):
    """``(kind, path)`` of every file ``producer`` writes, as written: each output, log file
    and its benchmark file."""
    benchmark = [producer.benchmark] if producer.benchmark else []
    kinds = {"output": producer.output, "log": producer.log, "benchmark": benchmark}
    return [(kind, str(f)) for kind, files in kinds.items() for f in files]


def _written(producer):
    """The files ``producer`` writes, logs and benchmark file included, as patterns judged by
    their real paths (see _judged; their wildcards' constraints inline); an output folder
    stands for everything inside it too."""
    found = [_judged(path) for _, path in _declared(producer)]
    folders = [_judged(str(f)) for f in producer.output if f.is_directory]
    # Joined as a path: the working directory (.) holds every path, none spelt with ./
    return [*found, *(Path(path, "{inside}").as_posix() for path in folders)]


def _shown(path):
    """The pattern ``path`` as written in a rule: its wildcards without their constraints."""
    return WILDCARD_REGEX.sub(lambda m: f"{{{m.group('name')}}}", path)


# A wildcard of a pattern, as one item: any text of one character or more.
_WILDCARD = None


@functools.cache
def _patterns_of(path):
    """``path`` as tuples of its characters, each wildcard as _WILDCARD or, where its
    constraint lists the names it takes (as the package's do), each of those in turn; one
    whose constraint matches the empty text (``{x,.*}``) also as nothing."""
    patterns = [()]
    for literal, constraint in _wildcard_pieces(path):
        names = _listed(constraint)
        ends = [(_WILDCARD,)] if names is None else [tuple(n) for n in names]
        if names is None and constraint and re.fullmatch(constraint, ""):
            ends.append(())
        if constraint is False:
            ends = [()]
        patterns = [(*p, *literal, *end) for p in patterns for end in ends]
    return tuple(patterns)


def _wildcard_pieces(path):
    """``(text, constraint)`` pieces of the file pattern ``path``: the text up to a wildcard
    and that wildcard's constraint (None without one), the last piece's False (no wildcard).
    """
    pieces, start = [], 0
    for found in WILDCARD_REGEX.finditer(path):
        pieces.append((path[start : found.start()], found.group("constraint")))
        start = found.end()
    return [*pieces, (path[start:], False)]


def _listed(constraint):
    """The names a wildcard constraint allows when it lists them (``a|b\\-c``, as
    :func:`_alternatives` writes, none for its pattern matching nothing), or None when it is
    any other pattern."""
    if constraint == _alternatives([]):
        return []
    if not constraint:
        return None
    names = [re.sub(r"\\(.)", r"\1", n) for n in re.split(r"(?<!\\)\|", constraint)]
    if "|".join(re.escape(n) for n in names) != constraint:
        return None
    return names


def _overlap(first, second):
    """Whether some path matches one pattern of each of :func:`_patterns_of`'s tuples."""
    return any(_meet(a, b) for a in first for b in second if _may_meet(a, b))


def _may_meet(first, second):
    """Whether the texts before the first wildcard and after the last agree (one's is the
    start, or the end, of the other's): most pairs of patterns differ there, and matching them
    item by item costs far more."""
    (head, tail), (other_head, other_tail) = _ends(first), _ends(second)
    return (head.startswith(other_head) or other_head.startswith(head)) and (
        tail.endswith(other_tail) or other_tail.endswith(tail)
    )


@functools.cache
def _ends(pattern):
    """The texts of ``pattern`` (a tuple of characters and wildcards) before its first
    wildcard and after its last: the whole text, twice, without one."""
    items = "".join("\0" if item is _WILDCARD else item for item in pattern)
    return items.split("\0", 1)[0], items.rsplit("\0", 1)[-1]


@functools.cache
def _meet(first, second):
    """Whether some path matches both patterns (tuples of characters and wildcards)."""

    @functools.cache
    def match(i, j):
        a = first[i] if i < len(first) else ""
        b = second[j] if j < len(second) else ""
        if a == "" and b == "":
            return True
        # A wildcard takes a character of the other pattern's, and then ends or goes on.
        if a is _WILDCARD and b is _WILDCARD:
            return match(i + 1, j + 1) or match(i, j + 1) or match(i + 1, j)
        if a is _WILDCARD:
            return b != "" and (match(i + 1, j + 1) or match(i, j + 1))
        if b is _WILDCARD:
            return a != "" and (match(i + 1, j + 1) or match(i + 1, j))
        return a != "" and a == b and match(i + 1, j + 1)

    return match(0, 0)


def _as_matched(path):
    """``path`` as Snakemake matches it against outputs, to find what writes it (relative to
    the working directory when it lies in it, without ``./`` or ``..``)."""
    path = os.path.normpath(path)
    if os.path.isabs(path) and Path(path).is_relative_to(Path.cwd()):
        path = os.path.relpath(path)
    return Path(path).as_posix()


def _judged(path):
    """``path`` as the checks judge it: by its real path (links followed, then ``..``, so that
    /proc/self/cwd/results/ or a link to it is results/), as under results/ when it lies in
    results/'s real folder (results/ may be a link to a larger disk), else relative to the
    working directory when it lies in it, else absolute; a pattern's wildcards are kept.
    """
    real = Path(os.path.realpath(path))
    folders = (
        (Path(os.path.realpath("results")), Path("results")),
        (Path.cwd(), Path()),
    )
    for folder, named in folders:
        if real.is_relative_to(folder):
            return (named / real.relative_to(folder)).as_posix()
    return real.as_posix()


def _alternatives(names):
    """A regex matching exactly one of ``names`` (never matches when the list is empty)."""
    return "|".join(re.escape(n) for n in names) or "(?!)"


wildcard_constraints:
    study=_alternatives(STUDIES),
    condition=r"[A-Za-z0-9_.\-]+",


def condition_ids(study):
    return [jb_config.condition_id(c) for c in jb_config.conditions(config, study)]


# Where the blind copy of a condition's dataset records the placement of each of its trials.
PLACEMENTS = "results/placements/{study}/{condition}.parquet"
# A condition's blind copy, what an external estimator reads (workflow/rules/interchange.smk).
BLIND = "results/blind/{study}/{condition}.parquet"


def dataset_file(study, condition):
    return f"results/datasets/{study}/{jb_config.condition_id(condition)}.parquet"


def placements_files(study, methods):
    """The placements of the blind copies of every condition of ``study``, which map the
    answers of an external estimator among ``methods`` back to the datasets' frame (none
    without one)."""
    return _for_external(PLACEMENTS, study, methods)


def blind_files(study, methods):
    """The blind copies of every condition of ``study`` that an external estimator among
    ``methods`` reads (none without one)."""
    return _for_external(BLIND, study, methods)


def _for_external(pattern, study, methods):
    """``pattern``'s file of every condition of ``study`` when ``methods`` include an external
    estimator, else none."""
    external = jb_config.estimator_names(config, study, source="external")
    if not set(methods) & set(external):
        return []
    return expand(pattern, study=study, condition=condition_ids(study))


def estimates_files(study, methods=None):
    """Every estimates file of a study (optionally only some estimators)."""
    methods = methods or jb_config.estimator_names(config, study)
    return expand(
        "results/estimates/{study}/{method}/{condition}.parquet",
        study=study,
        method=methods,
        condition=condition_ids(study),
    )


def listed_estimates_files(wildcards):
    """Every estimates file of the estimator ``wildcards.method`` of ``wildcards.study``; an
    estimator the study does not list is named with the list, not as missing files."""
    listed = jb_config.estimator_names(config, wildcards.study)
    if wildcards.method not in listed:
        raise ValueError(
            f"{wildcards.method!r} is not listed under studies.{wildcards.study} "
            f"({', '.join(listed)}): list it under estimators or external_estimators"
        )
    return estimates_files(wildcards.study, [wildcards.method])


POSES = "results/poses/{study}/{condition}.parquet"


def shared_poses(study, shared, per_condition=False):
    """The poses files an estimate job of ``study`` reads: those of its conditions (all, or the
    job's own with ``per_condition``) for a method in ``shared``, none for a method fitting
    its own poses."""

    def files(wildcards):
        if wildcards.method not in shared:
            return []
        conditions = [wildcards.condition] if per_condition else condition_ids(study)
        return expand(POSES, study=study, condition=conditions)

    return files


def _in_grid(study, condition):
    return jb_config.condition_id(condition) in set(condition_ids(study))


def paper_outputs(study):
    """``(paper, output)`` of every paper output of ``study`` this run can render; an output
    that draws a condition missing from the grid is skipped with a one-line note."""
    found = []
    for paper in papers_of_study(study):
        for output in paper.outputs:
            missing = [c for c in output.conditions if not _in_grid(study, c)]
            if missing:
                print(
                    f"note: {output.name} skipped: it draws {jb_config.condition_id(missing[0])}, "
                    f"which is not in this run's {study} grid",
                    file=sys.stderr,
                )
                continue
            found.append((paper, output))
    return found


PAPER_OUTPUTS = {study: paper_outputs(study) for study in STUDIES}
CAPTIONS = "results/report/captions/{name}.rst"
# The report's landing page: what the benchmark is, its headline findings and the run's machine.
FRONT_PAGE = "results/report/workflow.rst"


def category(study):
    """The report category of a study's outputs: its paper's title, or the study's name."""
    papers = papers_of_study(study)
    return papers[0].title if papers else f"Study {study}"


# Each output is shown in the report on a page of its own beside its caption.
PAGE = "results/report/pages/{name}.html"


def reported(path, name, group, subgroup):
    """``path`` flagged for `snakemake --report`, captioned by its generated caption file and
    listed in the report's menu by its name for people."""
    return report(
        path,
        caption=f"../../{CAPTIONS.format(name=name)}",
        category=group,
        subcategory=subgroup,
        labels={"output": jb_report.output_label(name)},
    )


def report_entries():
    """``(name, file shown, category, subcategory)`` of every output the report shows: each
    paper output's first file under its paper, each study's extended ranking, the comparison.
    """
    entries = []
    for study in STUDIES:
        for paper, output in PAPER_OUTPUTS[study]:
            group = "Figures" if output.kind == "figure" else "Tables"
            shown = next(iter(output.files.values()))
            entries.append((output.name, shown, paper.title, group))
        name = pipeline.extended_name(study)
        files = extended_files(study)
        ranking = "Extended ranking of every estimator"
        entries.append((name, files["html"], ranking, study_title(study)))
        entries.append((f"{name}_figure", files["png"], ranking, study_title(study)))
    comparison = "results/tables/published_comparison.html"
    entries.append(
        (
            "published_comparison",
            comparison,
            "Agreement with the papers",
            "Every value and claim",
        )
    )
    return entries


def summarised_tables():
    """Every table a caption's headline summarises, by name."""
    tables = {"published_comparison": "results/tables/published_comparison.csv"}
    for study in STUDIES:
        tables[pipeline.extended_name(study)] = extended_files(study)["csv"]
        for _, output in PAPER_OUTPUTS[study]:
            for name in output.summarises:
                tables[name] = f"results/tables/{name}.csv"
    return tables


def caption_names():
    """Every output with a caption: those the report shows."""
    return [name for name, *_ in report_entries()]


def extended_files(study):
    """The files of a study's extended ranking, by kind: its table and its figure."""
    name = pipeline.extended_name(study)
    tables = {kind: f"results/tables/{name}.{kind}" for kind in ("html", "csv", "md")}
    return {
        **tables,
        **{kind: f"results/figures/{name}.{kind}" for kind in ("png", "pdf")},
    }


def study_targets(study):
    """The collected results, every paper output of one study and its extended ranking."""
    outputs = [path for _, o in PAPER_OUTPUTS[study] for path in o.files.values()]
    extended = extended_files(study).values()
    return [f"results/collected/{study}.parquet", *outputs, *extended]


def all_targets():
    targets = [target for study in STUDIES for target in study_targets(study)]
    captions = [CAPTIONS.format(name=name) for name in caption_names()]
    pages = [PAGE.format(name=name) for name, *_ in report_entries()]
    return [
        *targets,
        "results/tables/published_comparison.csv",
        *captions,
        *pages,
        FRONT_PAGE,
    ]


# Provenance: every job that runs library code gets two parameters, and Snakemake reruns a job
# whose parameters changed. `code` is the fingerprint of its workflow script, the extension
# modules every job loads, every module of jointbench they can import and the package data
# those can read, schemas included (jointbench.fingerprint: read from import statements,
# docstrings and comments left out). `settings` holds the config values the job reads. Files a
# job reads are its inputs; those no job writes are also hashed by content into a third
# parameter, `sources` (track_sources).
SCRIPTS = Path(workflow.basedir, "workflow", "scripts")
EXTENSIONS = [Path(entry).resolve() for entry in config.get("extensions", [])]
# Python takes a module's cached bytecode as current by the source's size and time, which an edit
# can keep: every cache is made one checked by the source's content, before any job runs.
check_bytecode_by_content(*EXTENSIONS)
# Every paper's published values: the inputs of the jobs of its own study (published_files),
# left out of the code so that one paper's values rerun only those; named as files of the
# package, which each job is given (`code_plan`, plan_code_checks) to check its code with.
PUBLISHED = [get_paper(name).published for name in paper_names()]
CODE_INPUTS = data_names(PUBLISHED)
# What every job checks its code against the planned fingerprint with, besides its script and
# the run's extensions: the files left out of it, and the versions it was computed under (a job
# of a conda environment of its own names those that differ).
CODE_PLAN = {"inputs": CODE_INPUTS, "versions": dependency_versions()}


# Every script's fingerprint is computed in this process, which plans the jobs before any runs:
# one pass reads each file of the package once for them all (jointbench.fingerprint.OnePass).
FINGERPRINTS = OnePass()


@functools.cache
def script_code(script):
    """The fingerprint of the code a job running ``workflow/scripts/<script>.py`` can run."""
    return code_fingerprint(
        SCRIPTS / f"{script}.py", *EXTENSIONS, inputs=CODE_INPUTS, one_pass=FINGERPRINTS
    )


def plan_code_checks():
    """Give each rule with a code fingerprint (``code``, script_code) the parameter
    ``code_plan`` (CODE_PLAN): with it, the job computes the fingerprint again from the
    arguments script_code used, its script and the run's extensions being its own, and refuses
    to run code other than the planned (jointbench.jobs.check_planned_code). The Snakemake
    that plans the run hands every rule's fingerprint down to the jobs it starts: a cluster
    node reads the workflow again, and its ``code`` is the code as it is then."""
    planned = {}
    for producer in workflow.rules:
        names = producer.params.keys()
        if "code" not in names:
            continue
        # Snakemake would let this replace a rule's own parameter of that name.
        if "code_plan" in names:
            raise ValueError(
                f"rule {producer.name} has a parameter named 'code_plan', a name the "
                "workflow gives what each job checks its code fingerprint with; rename the "
                "rule's parameter"
            )
        producer.set_params(code_plan=CODE_PLAN)
        planned[producer.name] = producer.params.code
    if not workflow.remote_exec:
        jb_jobs.publish_planned_code(planned)


def study_settings(study, *keys):
    """The base seed and the ``keys`` of a study's config that a job of the study reads."""
    settings = config["studies"][study]
    return {"base_seed": config.get("base_seed"), **{k: settings.get(k) for k in keys}}


# What simulates a condition: the trials of each condition derive from these.
SIMULATION_KEYS = ("trials", "protocol")


def estimate_settings(study):
    """An estimate job's settings: the simulation's and its own estimator's options only, so
    that changing one estimator's options reruns that estimator alone."""
    options = config["studies"][study].get("options", {})
    return lambda w: {
        **study_settings(study, *SIMULATION_KEYS),
        "options": options.get(w.method, {}),
    }


def published_files(studies):
    """The published-values files of the papers of ``studies``: data a job reads."""
    return [
        str(paper.published) for study in studies for paper in papers_of_study(study)
    ]


def papers_to_render(study):
    """``(paper, outputs)`` for every paper of ``study`` with an output this run renders."""
    grouped = {}
    for paper, output in PAPER_OUTPUTS[study]:
        grouped.setdefault(paper.key, (paper, []))[1].append(output)
    return list(grouped.values())


def render_datasets(study):
    """The datasets the study's paper outputs draw, each once."""
    conditions = [c for _, output in PAPER_OUTPUTS[study] for c in output.conditions]
    return list(dict.fromkeys(dataset_file(study, c) for c in conditions))


def _output_key(name, kind):
    return f"{name}{pipeline.OUTPUT_SEPARATOR}{kind}"


def render_files(study):
    """Every file the study's render job writes, keyed ``<output>__<kind>``: its paper
    outputs' and its extended ranking's (the report shows them on pages, ``report_entries``).
    """
    files = {}
    for _, output in PAPER_OUTPUTS[study]:
        for kind, path in output.files.items():
            files[_output_key(output.name, kind)] = path
    name = pipeline.extended_name(study)
    for kind, path in extended_files(study).items():
        files[_output_key(name, kind)] = path
    return files


# Every output the report shows (``report_entries``), computed once.
REPORT_ENTRIES = report_entries()


# Where jobs write: an input elsewhere is a source (a published-values file, an external
# program, a config overlay), which no job remakes.
RESULTS = "results/"


def is_source(path):
    """Whether the input ``path`` is a source file rather than a job's result."""
    return not _as_matched(path).startswith(RESULTS)


def rule_sources(producer):
    """The parameter function giving each job of ``producer`` (a rule) the digests of its
    sources, its source inputs and the file its ``script`` directive runs, by path
    (jointbench.fingerprint.source_digests). It takes only the wildcards, as Snakemake compares
    only such parameters between runs."""

    def sources(wildcards):
        inputs = producer.expand_input(dict(wildcards.items()))[0]
        files = [_as_matched(f) for f in inputs if is_source(f)]
        if producer.script:
            program = os.path.join(
                producer.basedir.get_path_or_uri(secret_free=True), producer.script
            )
            files.append(_as_matched(program))
        return source_digests(files)

    return sources


def track_sources(user_rules):
    """Give each rule the parameter ``sources``, so that a source whose content changed reruns
    the job even when its time stamp is older than the job's outputs (a copy keeping times, a
    backup restored). For a rule of the user's (``user_rules``, by name) it also checks the
    job's files (see _kept_in_results): a parameter of its own would rerun every job of the
    user's already made."""
    for producer in workflow.rules:
        # Snakemake would let the digest replace a rule's own parameter of that name.
        if "sources" in producer.params.keys():
            raise ValueError(
                f"rule {producer.name} has a parameter named 'sources', a name the workflow "
                "gives the digest of each job's source files; rename the rule's parameter"
            )
        sources = rule_sources(producer)
        if producer.name in user_rules:
            sources = _kept_in_results(producer, sources)
        producer.set_params(sources=sources)


def limit_user_jobs(user_rules):
    """Give every job of the rules of the user's (``user_rules``, by name) the run's time limit,
    whatever its program's language: Snakemake runs its ``shell:`` or ``script:`` command with
    the limited shell (resource ``shell_exec``, jointbench.running.timelimit), a cluster gives
    it a ``runtime`` just above the limit, so that the limit stops it first, naming the rule,
    and a job the limit stopped fails with an error saying so. A ``run:`` block runs inside
    Snakemake, which no limit can stop without stopping the run: it is refused, naming the rule.
    """
    # A rule without a command (a target of the user's) runs nothing to limit.
    limited = [r for r in workflow.rules if r.name in user_rules and not r.norun]
    for producer in limited:
        if producer.is_run:
            raise ValueError(
                f"rule {producer.name} runs its code in a run"
                # Apart: Snakemake's linter reads "rule" and a colon on one line as a rule.
                ": block, inside Snakemake, where the "
                f"time limit of an external estimator's job ({timelimit.KEY}) cannot stop it: "
                "put the code in a script: or a shell: command (README, 'Adding an estimator')"
            )
    shells = confine_user_jobs(user_rules)
    for producer in limited:
        producer.resources["shell_exec"] = _ShellPath(shells[producer.name])
        producer.resources["runtime"] = timelimit.runtime_minutes(TIME_LIMIT_S)
        producer.run_func = _limited(producer.run_func, producer.name)


def confine_user_jobs(user_rules):
    """Tell the limited shell what each job of the rules of the user's (``user_rules``, by
    name) may open under results/ (jointbench.running.landlock, by the environment, as the
    limit), each rule its own grant. It may read the blind copies and their CSV form, and
    the inputs under results/ of its own rule's jobs that the run's external estimators need;
    read and write
    the folders its own rule's files (outputs, logs, benchmark files) go in, as those jobs
    spell them, and as their rule spells them (_spelt_folders); nothing else there, not the
    datasets, the placements, the built-in estimators' files nor anything made from them, and
    not the folders of another rule of the user's, whose answers a program could copy or
    spoil. A folder in or below which the benchmark writes too is refused, as its job could
    write over the benchmark's files there (see _refuse_the_benchmarks). Where the kernel has
    no Landlock the jobs run unconfined, and the run says so once, here.

    Returns, per rule of the user's by name, the shell its jobs run with (_rule_shell), which
    hands the limited shell its rule's confinement; the run's environment holds the least,
    the blind copies alone."""
    users = [r for r in workflow.rules if r.name in user_rules]
    opened = _opened_by_users(users)
    everyone = {}
    for _, written in opened.values():
        for folder, first in written.items():
            everyone.setdefault(folder, first)
    _refuse_the_benchmarks(everyone, _package_rules(user_rules))
    hidden = os.path.realpath(RESULTS)
    os.environ[landlock.VARIABLE] = landlock.encoded(
        landlock.Confinement(hidden, _real_paths(READABLE), [])
    )
    shells = {}
    for producer in users:
        inputs, written = opened[producer.name]
        confinement = landlock.Confinement(
            hidden,
            _real_paths(_readable(inputs, written, users, everyone)),
            _real_paths(written),
        )
        shells[producer.name] = _rule_shell(producer.name, confinement)
    if users and not landlock.abi_version():
        logger.warning(NOT_CONFINED)
    return shells


# What the run says where the kernel cannot confine the jobs of external estimators.
NOT_CONFINED = (
    "jointbench: this kernel has no Landlock (Linux 5.13 or later, enabled): the programs "
    "of external estimators run unconfined, and may open any file under results/, the "
    "truth too (README, 'Adding an estimator')"
)

# Where each rule of the user's gets the shell its jobs run with (_rule_shell), beside
# Snakemake's own records, outside results/, which no job of the user's may write in.
RULE_SHELLS = os.path.join(".snakemake", "jointbench", "shells")


# How landlock.VARIABLE spells a confinement marked inherited (landlock.confine).
_INHERITED = '"inherited": true'


def _rule_shell(name, confinement):
    """The absolute path of the shell the jobs of the rule ``name`` run with, a script named bash
    (Snakemake gives its prefix to a shell of that name alone) that runs the limited shell
    (jointbench.running.timelimit) with ``confinement`` in landlock.VARIABLE, so that each
    rule's jobs get their own. Written where it differs (_replaced). Where it cannot be, and
    none was written before, no job can run either (a read-only checkout): the path is returned
    for a command that runs none (--list-rules), and a job would find no shell there. One
    written before that cannot be replaced is refused, naming it."""
    path = os.path.abspath(os.path.join(RULE_SHELLS, _shell_folder(name), "bash"))
    variable = landlock.VARIABLE
    text = (
        "#!/bin/sh\n"
        # The name as JSON: ASCII on one line, whatever it holds (a line break would end the
        # comment and run the rest).
        f"# The limited shell of the jobs of rule {json.dumps(name)}, with what they may "
        "open under "
        "results/ (written by workflow/rules/common.smk as the workflow loads).\n"
        "# Within a job (a script's shell() call) the confinement its keeper handed down is\n"
        "# kept: the job cannot widen it, nor list again what the keeper listed.\n"
        f'case "${{{variable}-}}" in\n'
        f"*{shlex.quote(_INHERITED)}*) ;;\n"
        f"*) {variable}={shlex.quote(landlock.encoded(confinement))}; export {variable} ;;\n"
        "esac\n"
        f'exec {shlex.quote(timelimit.LIMITED_SHELL)} "$@"\n'
    )
    if os.path.isfile(path) and Path(path).read_text() == text:
        return path
    try:
        _replaced(path, text)
    except OSError as error:
        if os.path.lexists(path):
            raise ValueError(
                f"{path} cannot be replaced ({error.strerror}): the jobs of rule {name} would "
                "run with the confinement written there before, not this workflow's; remove "
                "it, or make .snakemake/ writable"
            ) from error
    return path


# A rule's name as its shell's folder is named when it is plain: lower-case ASCII letters,
# digits and underscores, short enough for any file system.
_PLAIN_RULE_NAME = re.compile(r"[a-z0-9_]{1,100}")


def _shell_folder(name):
    """The folder, in RULE_SHELLS, of the shell of the rules named ``name``. A plain name
    (_PLAIN_RULE_NAME, as the workflow's rules are named) is its own; any other (Snakemake's
    ``name:`` takes any string: a path, a line break, a name longer than a file's, letters
    beyond ASCII, another's name in other case) its plain characters in lower case, at most
    64, then a hyphen, which no plain name holds, and a digest of the name itself. Names
    differing in anything, case included, get folders differing in more than case, on one
    line, inside RULE_SHELLS."""
    if _PLAIN_RULE_NAME.fullmatch(name):
        return name
    plain = "".join(
        c for c in name.lower() if c in "abcdefghijklmnopqrstuvwxyz0123456789_"
    )
    return f"{plain[:64]}-{hashlib.sha256(name.encode('utf-8', 'surrogatepass')).hexdigest()[:16]}"


def _replaced(path, text):
    """Write ``text`` to an executable file at ``path``, whole and then moved into place, from
    a file of a name no other process has: the Snakemake processes of a cluster's jobs load the
    workflow at once, on hosts whose process ids may be the same."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix="bash.", dir=os.path.dirname(path))
    try:
        with os.fdopen(handle, "w") as file:
            file.write(text)
        os.chmod(temporary, 0o755)
        os.replace(temporary, path)
    finally:
        # Left only where the move failed.
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)


def _opened_by_users(users):
    """Per rule of ``users`` (rules of the user's; see confine_user_jobs), by name, ``(inputs,
    written)``: the inputs under results/ of its jobs, and the folders they write in, each
    with ``(rule, kind, path)`` of a file written there; paths relative to the working
    directory."""
    opened = {producer.name: (set(), {}) for producer in users}
    for producer, wildcards in _jobs_of_external_estimators(users):
        inputs, written = opened[producer.name]
        for kind, path in _declared(producer):
            path = apply_wildcards(path, wildcards)
            written.setdefault(os.path.dirname(path), (producer.name, kind, path))
        read = [_as_matched(str(f)) for f in producer.expand_input(wildcards)[0]]
        inputs.update(f for f in read if f.startswith(RESULTS))
    for producer in users:
        _, written = opened[producer.name]
        for kind, path in _declared(producer):
            for folder in _spelt_folders(os.path.dirname(path)):
                written.setdefault(folder, (producer.name, kind, path))
    return opened


def _spelt_folders(folder):
    """The folders a job of a rule of the user's may write in by the pattern ``folder``,
    whether or not the run's studies list its estimator (a target asked for by name): itself
    where it holds no wildcard; one per study of the config where ``{study}`` is its only one
    (``results/estimates/{study}/<name>/``, as the README's rules write); none where another
    wildcard names it, which no job spells before it runs."""
    names = {match.group("name") for match in WILDCARD_REGEX.finditer(folder)}
    if not names:
        return [folder]
    if names == {"study"}:
        return [
            apply_wildcards(folder, {"study": study}) for study in config["studies"]
        ]
    return []


def _readable(inputs, writable, users, shared):
    """What the jobs of one rule of ``users`` may read under results/, the blind copies
    (READABLE) and those of its ``inputs`` the checks let it read (check_external_rules has
    refused any other) that lie in none of those folders nor of its own ``writable`` ones,
    which are granted whole: one in a folder of ``shared`` (those every rule of the user's
    writes in) by that folder, to be read, any other by itself, so that what the jobs are
    handed does not grow with the conditions."""
    granted = tuple(f"{folder.rstrip('/')}/" for folder in (*READABLE, *writable))
    found = set(READABLE)
    for f in inputs:
        if f.startswith(granted) or _refusal(f, users) is not None:
            continue
        folder = next((d for d in shared if f.startswith(f"{d.rstrip('/')}/")), None)
        found.add(f if folder is None else folder)
    return found


def _real_paths(paths):
    return sorted({os.path.realpath(p) for p in paths})


def _refuse_the_benchmarks(written, package):
    """Stop when one of the folders ``written`` (each with ``(rule, kind, path)`` of a file a
    rule of the user's writes there) is one in which, or below which, a rule of ``package``
    (the benchmark's rules) can write a file, naming both: the job may write in its folder,
    and so over any file of the benchmark's in or below it (a built-in estimator's logs or
    estimates, the datasets), which the kernel cannot tell from its own."""
    theirs = _WrittenIndex(package)
    for folder, (rule, kind, path) in written.items():
        overlapping = theirs.first_overlap(_patterns_of(f"{folder}/{{inside}}"))
        if overlapping is not None:
            other, file = overlapping
            raise ValueError(
                f"rule {rule} writes its {kind} {path} in {folder}/, where rule "
                f"{other.name} of the benchmark writes ({_shown(file)}): its job could "
                "write over the benchmark's files there. A rule of yours writes its files "
                "under results/, in a folder of its own (README, 'Adding an estimator')"
            )


def _jobs_of_external_estimators(users):
    """``(rule, wildcards)`` of each job of ``users`` (rules of the user's) that writes the
    estimates of an external estimator of the run, or a file one of those jobs reads, at
    any remove."""
    todo = []
    for study in STUDIES:
        for name in jb_config.estimator_names(config, study, source="external"):
            for parquet in estimates_files(study, [name]):
                for file in (parquet, parquet.removesuffix(".parquet") + ".csv"):
                    todo += [(u, file) for u in users if _produces(u, file)]
    seen = set()
    while todo:
        producer, file = todo.pop()
        wildcards, job = _job(producer, file)
        if job in seen:
            continue
        seen.add(job)
        yield producer, wildcards
        for read in producer.expand_input(wildcards)[0]:
            spelt = _as_matched(str(read))
            todo += [(u, spelt) for u in users if _produces(u, spelt)]


def _limited(run, name):
    """The run function ``run`` of rule ``name``, whose job, when the limited shell reports
    that the time limit stopped its command, fails with an error naming the rule, the job's
    wildcards, the limit and the key to raise, not a bare exit status. The error is written
    to the job's logs too: the run's closing summary names those, and in a long run the error
    itself is printed far above it."""

    @functools.wraps(run)
    def limited(input, output, params, wildcards, threads, resources, log, *rest):
        start = time.monotonic()
        try:
            return run(input, output, params, wildcards, threads, resources, log, *rest)
        except subprocess.CalledProcessError as error:
            # The status alone is not the limit's: a program may exit with it by itself.
            stopped = time.monotonic() - start >= TIME_LIMIT_S
            if error.returncode != timelimit.EXPIRED or not stopped:
                raise
            named = dict(wildcards.items())
            message = timelimit.expired_message(name, named, TIME_LIMIT_S)
            _append_to_logs(log, message)
            raise TimeLimitExceeded(message) from None

    return limited


def _append_to_logs(logs, line):
    """Append ``line`` to each of a job's log files ``logs`` (Snakemake's list of them), after
    whatever its program wrote there."""
    for path in logs:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        with open(path, "a") as log:
            print(line, file=log)


class TimeLimitExceeded(Exception):
    """A job of an external estimator stopped at the run's time limit."""


class _ShellPath(str):
    """The path of a shell, as the resource ``shell_exec`` takes it: Snakemake (9.27) writes
    that resource into the preamble of a ``script:`` job as Python code, unquoted, so it is
    formatted as a Python string there; pickled (the script's ``snakemake.resources``) and
    used as a path, it is the plain path."""

    def __format__(self, spec):
        return format(repr(str(self)), spec)

    def __reduce__(self):
        return str, (str(self),)


# Snakemake reruns a job whose parameters (its code, its settings, its sources) changed only by
# its record of the job that made the files (.snakemake/metadata); a file it holds no record of
# (that folder deleted, results/ copied from another clone or a cluster) it takes as current,
# whatever made it. Such files are refused before any job runs: no record, no known provenance.
# A file a killed job left is marked incomplete instead, which Snakemake itself refuses or remakes.
RECORDS = Path(".snakemake", "metadata")
INCOMPLETE = Path(".snakemake", "incomplete")


def _record_path(folder, path):
    """Where Snakemake's file store (its default) keeps, in ``folder``, what it knows of the
    output ``path``: the URL-safe base64 of the path, cut into names the file system allows.
    """
    encoded = base64.urlsafe_b64encode(path.encode()).decode()
    longest = os.pathconf(".", "PC_NAME_MAX") - 1 if os.name == "posix" else 254
    pieces = [encoded[i : i + longest] for i in range(0, len(encoded), longest)]
    return folder.joinpath(*[f"@{p}" for p in pieces[:-1]], pieces[-1])


def _unrecorded(path):
    """Whether Snakemake holds neither a record of the output ``path`` nor a mark that the job
    writing it did not finish."""
    return not any(_record_path(f, path).exists() for f in (RECORDS, INCOMPLETE))


def _option_given(argv, option, short=None):
    """Whether a Snakemake command line (``sys.argv[1:]``) gives the flag ``option`` (or its
    ``short`` form alone): the workflow loads before Snakemake hands it its settings. Spelt in
    full or shortened as Snakemake's parser takes it (a prefix, which must name one option).
    """
    return any(
        argument == short or (len(argument) > 3 and option.startswith(argument))
        for argument in argv
    )


def _persistence_backend(argv):
    """The store of records a Snakemake command line (``sys.argv[1:]``) names, or None."""
    for i, argument in enumerate(argv):
        if argument.startswith("--persistence-backend="):
            return argument.partition("=")[2]
        if argument == "--persistence-backend" and i + 1 < len(argv):
            return argv[i + 1]
    return None


def unrecorded_results():
    """The files under results/ that a rule writes and that Snakemake holds no record of."""
    if not Path("results").is_dir():
        return []
    products = [o for producer in workflow.rules for o in producer.output]
    return [
        name
        for name in (
            p.as_posix() for p in sorted(Path("results").rglob("*")) if p.is_file()
        )
        if _unrecorded(name) and any(o.match(name) for o in products)
    ]


def refuse_unrecorded_results():
    """Stop the run, before any job, when results/ holds files of the workflow's rules that
    Snakemake has no record of (unrecorded_results): it would take them as current. They are
    listed in UNRECORDED_LIST, which the message names with the two ways out: recording them as
    they are (``--touch --force`` on them), which such a command may do unrefused, and
    deleting them. Not on a cluster node, which plans nothing, nor with a store of records
    other than Snakemake's default one, nor for a command that runs no job and takes no file as
    current (RUNS_NO_JOB)."""
    argv = sys.argv[1:]
    if (
        workflow.remote_exec
        or _option_given(argv, "--touch", "-t")
        or any(_option_given(argv, *flag) for flag in RUNS_NO_JOB)
        or _persistence_backend(argv) not in (None, "file")
    ):
        return
    found = unrecorded_results()
    if found:
        raise ValueError(
            f"results/ holds {len(found)} files Snakemake has no record of (e.g. {found[0]}), "
            f"{_listed_in(found)}: their code, config and data are unknown, and Snakemake "
            f"would take them as current ({RECORDS} lost, results/ copied from elsewhere, or a "
            "run with --drop-metadata, which records nothing). Delete them and run again, "
            f"which makes them anew: (cd {shlex.quote(os.getcwd())} && xargs -d '\\n' rm -- "
            f"< {UNRECORDED_LIST}). Or, only if this very code, config and data made them, "
            "record them as they are: snakemake --touch --force "
            f"$(cat {_where(UNRECORDED_LIST)}), with this run's other options."
        )


# Snakemake's flags (and short forms) of commands that run no job and take no file as current:
# the rules listed, or the workflow's output deleted, which is one way out of results without
# a record.
RUNS_NO_JOB = (
    ("--list-rules", "-l"),
    ("--list-target-rules", "--lt"),
    ("--delete-all-output",),
)


# Where refuse_unrecorded_results lists the files it refuses, one a line, for the commands its
# message gives.
UNRECORDED_LIST = os.path.join(".snakemake", "jointbench", "unrecorded.txt")


def _listed_in(files):
    """Write ``files`` to UNRECORDED_LIST, one a line, and say where: "listed in ...", or,
    where it cannot be written (a read-only checkout), the files themselves."""
    try:
        _replaced(UNRECORDED_LIST, "".join(f"{name}\n" for name in files))
    except OSError:
        return "listed here: " + " ".join(files)
    return f"listed in {_where(UNRECORDED_LIST)}"


def _where(path):
    """``path`` as a shell reads it from any folder, absolute and quoted where it must be: a
    run given --directory works in a folder its user is not in, whose path may hold a
    space."""
    return shlex.quote(os.path.abspath(path))


def refuse_dropped_metadata(kept=None):
    """Stop a run with ``--drop-metadata`` before any job: it records nothing of the jobs it
    runs, and leaves each file it rewrites with the record of the job that made it before,
    which describes other code, config or data; reverting to those would leave the file, made
    by neither, current. ``kept``: whether Snakemake keeps records, once it has handed the
    workflow its settings (``onstart``, which a profile's setting reaches too); before, as the
    workflow loads, read from the command line. Not on a cluster node, whose job Snakemake
    hands the option to."""
    if kept is None:
        kept = not _option_given(sys.argv[1:], "--drop-metadata")
    if not workflow.remote_exec and not kept:
        raise ValueError(
            "--drop-metadata is refused: a run with it records nothing of the jobs it runs, "
            "and leaves each file it rewrites with the record of the job that made it before, "
            "of other code, config or data, which Snakemake would then take the file as made "
            "by; run without it"
        )
