"""The Snakemake command a message asks the user to run, with the options of the run it is in.

A job that meets a file it cannot read tells the user how to regenerate it. That advice must
run the same workflow on the same config: a ``--forcerun`` without the user's ``--configfile``
would rebuild the default config's results, not theirs. The Snakemake process records the
options that choose the workflow, its config and its executor (:func:`record`, called by the
rules) in the environment, which local jobs and SLURM jobs inherit, and a job words its advice
with :func:`snakemake_command`.
"""

from __future__ import annotations

import argparse
import os
import shlex
from collections.abc import MutableMapping, Sequence

__all__ = [
    "ENVIRONMENT_VARIABLE",
    "check_options",
    "record",
    "repeated_options",
    "snakemake_command",
    "workflow_options",
]

#: Where the Snakemake process leaves its options for its jobs, as a shell-quoted string.
ENVIRONMENT_VARIABLE = "JOINTBENCH_SNAKEMAKE_OPTIONS"

# The options that decide which workflow runs, on which config and where; each with Snakemake's
# own spellings and number of values. Any other option (targets, --dry-run, --forcerun, …)
# belongs to one invocation, not to the run a follow-up command must repeat.
_OPTIONS = (
    (("--snakefile", "-s"), None),
    (("--directory", "-d"), None),
    (("--configfile", "--configfiles"), "+"),
    (("--config", "-C"), "*"),
    (("--profile",), None),
    (("--workflow-profile",), None),
    (("--cores", "-c"), None),
    (("--jobs", "-j"), None),
)
# Without any of these, Snakemake refuses to run; the README's default.
_PARALLELISM = ("--cores", "--jobs", "--profile")
_DEFAULT_PARALLELISM = ("-j2",)


def _parser() -> argparse.ArgumentParser:
    # No abbreviations: Snakemake accepts them, but guessing which option one meant is worse
    # than leaving it out of the advice.
    parser = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
    for names, nargs in _OPTIONS:
        parser.add_argument(*names, dest=names[0], nargs=nargs)
    return parser


def workflow_options(argv: Sequence[str]) -> list[str]:
    """The options of a Snakemake command line (``sys.argv[1:]``) that a follow-up command must
    repeat to act on the same run: snakefile, directory, config files and values, profiles and
    parallelism, in their long spelling; ``-j2`` when it gives no parallelism."""
    given, _ = _parser().parse_known_args(list(argv))
    options = []
    for names, nargs in _OPTIONS:
        value = getattr(given, names[0])
        if value is None or value == []:
            continue
        options += [names[0], *value] if nargs else [names[0], value]
    if not set(options) & set(_PARALLELISM):
        options = [*_DEFAULT_PARALLELISM, *options]
    return options


def repeated_options(argv: Sequence[str]) -> list[tuple[str, list[list[str]]]]:
    """Each option of a Snakemake command line (``sys.argv[1:]``) that takes a list of values
    (config files, config values) and is given more than once, in its long spelling, with the
    values of every time it is given, in order."""
    parser = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
    listed = [(names, nargs) for names, nargs in _OPTIONS if nargs]
    for names, nargs in listed:
        parser.add_argument(*names, dest=names[0], nargs=nargs, action="append")
    given, _ = parser.parse_known_args(list(argv))
    times = [(names[0], getattr(given, names[0]) or []) for names, _ in listed]
    return [(option, values) for option, values in times if len(values) > 1]


def check_options(argv: Sequence[str]) -> None:
    """``ValueError`` naming an option of ``argv`` given more than once
    (:func:`repeated_options`): Snakemake keeps the values of its last time alone, and a config
    file or config value given before would be dropped without a word, the run made on another
    config than the one its command line shows."""
    for option, values in repeated_options(argv):
        dropped = "; ".join(shlex.join(each) for each in values[:-1])
        every = shlex.join([value for each in values for value in each])
        raise ValueError(
            f"{option} is given {len(values)} times: Snakemake keeps the last alone "
            f"({shlex.join(values[-1])}) and would drop {dropped}; give them all after one "
            f"{option}: {option} {every}"
        )


def record(argv: Sequence[str], environ: MutableMapping[str, str] = os.environ) -> None:
    """Leave the :func:`workflow_options` of ``argv`` to the jobs, unless a Snakemake process
    above this one already has: a SLURM job re-reads the rules under an internal command line
    of its own, and the user's is the one to repeat."""
    environ.setdefault(ENVIRONMENT_VARIABLE, shlex.join(workflow_options(argv)))


def snakemake_command(*arguments: str, environ: MutableMapping[str, str] = os.environ) -> str:
    """``snakemake`` with the recorded options of this run and ``arguments``, ready to paste
    in a shell (``-j2`` alone outside a recorded run)."""
    options = environ.get(ENVIRONMENT_VARIABLE, shlex.join(_DEFAULT_PARALLELISM))
    return " ".join(["snakemake", options, shlex.join(arguments)])
