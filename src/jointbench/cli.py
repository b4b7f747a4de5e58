"""Command line: ``jointbench inspect``, ``fit``, ``snapshot`` and ``readme``.

Every expected failure (a missing or unreadable file, an unknown label or method, an artefact
in the data) is one line on stderr naming the file, the label and the frame, and exit code 2;
never a traceback. With ``--method all`` a method that cannot fit the data gets a row whose
status says why (``failed: ...``) and the others still run; the exit code is 2 only when every
method failed.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import sys
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

import jointbench
from jointbench.comparison.readme_standout import (
    STANDOUT_BLOCK,
    read_ensembles,
    standout_block,
)
from jointbench.comparison.snapshot import (
    VERDICTS_BLOCK,
    readme_blocks,
    reproduction_summary,
    snapshot_table,
    update_readme,
)
from jointbench.configuration.config import open_sources, read_sources, study_names
from jointbench.ensembles.named import ensembles
from jointbench.ensembles.verdicts import PROTOCOL_SHARES, standout_summary
from jointbench.estimators.registry import KINDS, get
from jointbench.estimators.validation import MAX_SPAN_MM
from jointbench.io import ARTEFACT_POLICIES, DEFAULT_METHODS, Recording, prepare, read
from jointbench.io.fit import CENTER_IS, NOT_DETERMINED, SD_NAMES, SD_STATED, point_precision
from jointbench.io.segments import HELD_SAMPLES, LAB_FIXED_FLAG, LAB_FIXED_MM
from jointbench.papers import paper_labels
from jointbench.precompile import precompile
from jointbench.report import (
    dry_run_pending,
    jobs_named,
    missing_files_named,
    readme_headlines,
    run_missing_outputs,
)
from jointbench.uncertainty import check_resampling

#: The config every run starts from (the Snakefile's ``configfile``), relative to the run's
#: directory.
DEFAULT_CONFIG = Path("config/config.yaml")

__all__ = ["main"]

FORMATS = ("table", "json", "csv")


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Keeps the method list's line breaks and shows every option's default (when it has one)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        # An empty default (a repeatable option's) says nothing worth a line.
        if action.default not in (None, argparse.SUPPRESS, []) and "%(default)" not in text:
            text += " (default: %(default)s)"
        return text


def _summary(function) -> str:
    """The first sentence of a docstring, on one line; a clause before ``:`` when that alone
    says enough."""
    paragraph = (function.__doc__ or "").strip().split("\n\n")[0]
    text = " ".join(paragraph.split()).replace("``", "")
    text = re.split(r"\.\s+(?=[A-Z])", text)[0].rstrip(".")
    clause = text.split(": ")[0]
    return clause if len(clause) >= 30 else text


def _method_list() -> str:
    lines = ["methods (--kind, then --method; 'all' runs every method of the kind):"]
    for kind in KINDS:
        lines.append(f"  {kind} (default {DEFAULT_METHODS[kind]}):")
        for name in jointbench.methods(kind):
            lines.append(f"    {name:<20} {_summary(get(kind, name))}")
    return "\n".join(lines)


def _open_run(args: argparse.Namespace) -> Mapping:
    """The run's config, as the workflow opens it: the repository's config and each
    ``--configfile`` over it, checked against the schema, then extensions loaded (relative to
    the working directory), the rest checked and its named protocols read
    (:func:`~jointbench.ensembles.named.ensembles`); returns it."""
    if not DEFAULT_CONFIG.is_file():
        # Said in full: `fit` is often run outside the run's folder, where this is not obvious.
        raise ValueError(
            f"{DEFAULT_CONFIG}: no such file in {Path.cwd()}; the run's config, which each "
            "--configfile updates as snakemake's does, is read from the folder the run is in: "
            "run jointbench there"
        )
    sources = read_sources([DEFAULT_CONFIG, *args.configfile])
    config = open_sources(sources)
    # Its named protocols, which a run under Snakemake reads as it starts: a mistake in one
    # refuses the config here too.
    ensembles(config, sources)
    return config


def _snapshot(args: argparse.Namespace) -> int:
    config = _open_run(args)
    if _stale(args, "snapshot"):
        return 1
    table = snapshot_table(args.results / "collected", study_names(config))
    args.output.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.output, index=False, float_format="%.12g")
    print(f"wrote {len(table)} values to {args.output}")
    return 0


def _precompile(args: argparse.Namespace) -> int:
    total = 0.0
    for kind, method, seconds in precompile():
        print(f"{kind:<13} {method:<20} {seconds:8.2f} s")
        total += seconds
    print(f"compiled (or loaded from the cache) every method's kernels in {total:.1f} s")
    return 0


def _readme(args: argparse.Namespace) -> int:
    comparison_path = args.results / "tables" / "published_comparison.csv"
    if not comparison_path.is_file():
        print(
            f"jointbench: no {comparison_path}: run `snakemake -j2` first to produce the "
            "results the README summarises",
            file=sys.stderr,
        )
        return 1
    if not args.readme.is_file():
        raise ValueError(f"{args.readme}: no such file")
    _open_run(args)
    if _stale(args, "readme"):
        return 1
    comparison = pd.read_csv(comparison_path)
    blocks = {
        "summary": (
            "reproduction-summary",
            reproduction_summary(comparison, paper_labels()),
        ),
        **{
            name: (name, headline)
            for name, headline in readme_headlines(
                args.results / "tables", readme_blocks(args.readme)
            ).items()
        },
    }
    if STANDOUT_BLOCK in readme_blocks(args.readme):
        blocks["what stands out"] = (
            STANDOUT_BLOCK,
            standout_block(comparison, read_ensembles(args.results), paper_labels()),
        )
    for what, (block, text) in blocks.items():
        changed = update_readme(args.readme, text, block=block)
        print(f"{args.readme}: {what} {'updated' if changed else 'already current'}")
    verdicts_path = args.results / "tables" / "verdicts.csv"
    if not verdicts_path.is_file():
        print(
            f"{args.readme}: verdicts over seeds left as they are: no {verdicts_path} "
            "(`snakemake -j2 verdicts` writes it)"
        )
        return 0
    pending = _verdicts_pending(args)
    if pending:
        jobs = jobs_named(pending)
        print(
            f"jointbench: {args.readme}: verdicts over seeds left as they are: {verdicts_path} "
            "is not up to date with the code, config and data that make it (`snakemake -j2` "
            f"does not remake it); `{_verdicts_command(args)}` would redo {jobs}: run it first",
            file=sys.stderr,
        )
        return 1
    missing = _verdicts_missing(args)
    if missing:
        rules = sorted(set(missing.values()))
        rerun = shlex.join(
            ["snakemake", "-j2", "verdicts", "--forcerun", *rules, *_config_options(args)]
        )
        print(
            f"jointbench: {args.readme}: verdicts over seeds left as they are: "
            f"{missing_files_named(missing)}, such as a failed job's outputs, which a run "
            f"does not remake while the verdicts made from them are present: run `{rerun}` first",
            file=sys.stderr,
        )
        return 1
    protocols_path = args.results / PROTOCOL_SHARES
    protocols = pd.read_csv(protocols_path) if protocols_path.is_file() else None
    summary = standout_summary(pd.read_csv(verdicts_path), protocols)
    changed = update_readme(args.readme, summary, VERDICTS_BLOCK)
    print(f"{args.readme}: verdicts over seeds {'updated' if changed else 'already current'}")
    return 0


def _config_options(args: argparse.Namespace) -> list[str]:
    """The command's config files as one ``--configfile`` option, as Snakemake takes them: it
    keeps the last of several such options."""
    return ["--configfile", *map(str, args.configfile)] if args.configfile else []


def _verdicts_command(args: argparse.Namespace) -> str:
    """The command that remakes the run's verdicts over seeds."""
    return shlex.join(["snakemake", "-j2", "verdicts", *_config_options(args)])


def _verdicts_pending(args: argparse.Namespace) -> dict[str, int]:
    """The jobs of each rule that the run's ``verdicts`` target would redo
    (:func:`_pending`)."""
    return _pending(args, ["verdicts"], "jointbench readme")


def _verdicts_missing(args: argparse.Namespace) -> dict[str, str]:
    """The files of the run's ``verdicts`` target that are missing though a run would not
    remake them (:func:`_missing`)."""
    return _missing(args, ["verdicts"], "jointbench readme")


def _default_pending(args: argparse.Namespace, command: str) -> dict[str, int]:
    """The jobs of each rule that the run's default target, ``snakemake -j2``, would redo
    (:func:`_pending`), which jointbench ``command`` asks."""
    return _pending(args, [], f"jointbench {command}")


def _pending(args: argparse.Namespace, targets: list[str], what: str) -> dict[str, int]:
    """The jobs of each rule that a run of ``targets`` would redo: a dry run by the
    ``snakemake`` beside this interpreter, in the run's folder (the working directory), with
    the command's config files, which ``what`` asks; ``ValueError`` where there is no such
    ``snakemake``."""
    snakemake = _run_snakemake(what)
    return dry_run_pending([snakemake, *targets, "--dry-run", *_config_options(args)], what)


def _missing(args: argparse.Namespace, targets: list[str], what: str) -> dict[str, str]:
    """``{file: rule}`` of the files of a run of ``targets`` that are missing though it would
    not remake them, a failed job's outputs (:func:`jointbench.report.run_missing_outputs`),
    by the ``snakemake`` beside this interpreter, which ``what`` asks."""
    summary = [_run_snakemake(what), *targets, "--summary", *_config_options(args)]
    return run_missing_outputs(summary, what)


def _run_snakemake(what: str) -> str:
    """The ``snakemake`` beside this interpreter, which ``what`` asks about the run's results;
    ``ValueError`` where there is none."""
    snakemake = Path(sys.executable).with_name("snakemake")
    if not snakemake.is_file():
        raise ValueError(
            f"no {snakemake}: {what} asks the run's snakemake whether the results it reads "
            "are up to date; install the project's environment"
        )
    return str(snakemake)


#: The files Snakemake reads the workflow from, in the folder it runs in, without ``-s``.
_SNAKEFILES = ("Snakefile", "snakefile", "workflow/Snakefile", "workflow/snakefile")


def _stale(args: argparse.Namespace, command: str) -> bool:
    """Whether the results jointbench ``command`` reads are not up to date with the code,
    config and data that make them, as the dry run of the run's default target says, or miss
    files a failed job left out (:func:`_incomplete`); if so, it says which jobs would be
    redone or which files are missing, and by what command. Results that are not the
    ``results/`` of a workflow in the working directory cannot be asked about: that is said,
    and they count as current."""
    workdir = Path.cwd()
    ours = args.results.resolve() == (workdir / "results").resolve()
    if not (ours and any((workdir / name).is_file() for name in _SNAKEFILES)):
        print(
            f"jointbench {command}: not checked whether {args.results} is up to date: it is "
            f"not the results/ of a workflow in {workdir}",
            file=sys.stderr,
        )
        return False
    pending = _default_pending(args, command)
    if not pending:
        return _incomplete(args, command)
    jobs = jobs_named(pending)
    rerun = shlex.join(["snakemake", "-j2", *_config_options(args)])
    print(
        f"jointbench {command}: {args.results} is not up to date with the code, config and "
        f"data that make it; `{rerun}` would redo {jobs}: run it first",
        file=sys.stderr,
    )
    return True


def _incomplete(args: argparse.Namespace, command: str) -> bool:
    """Whether files of the run that jointbench ``command`` reads are missing though a run
    would not remake them (:func:`_missing`): the results made from them are from before the
    job that failed. If so, it names them and the command that makes them again."""
    missing = _missing(args, [], f"jointbench {command}")
    if not missing:
        return False
    rules = sorted(set(missing.values()))
    rerun = shlex.join(["snakemake", "-j2", "--forcerun", *rules, *_config_options(args)])
    print(
        f"jointbench {command}: {missing_files_named(missing)}, such as a failed job's "
        "outputs, which a run does not remake while the files made from them are present: "
        f"{args.results} holds what was made before; run `{rerun}` first",
        file=sys.stderr,
    )
    return True


def _read(path: str) -> Recording:
    """The recording at ``path`` (:func:`~jointbench.io.read`), its warnings (a unit the file
    does not state, frames zero-filled past its end) printed first, whatever follows."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        recording = read(path)
    for warning in caught:
        print(f"jointbench: warning: {warning.message}", file=sys.stderr)
    return recording


def _inspect(args: argparse.Namespace) -> int:
    recording = _read(args.file)
    gaps = recording.gaps()
    last = recording.first_frame + recording.n_frames - 1
    if args.format == "json":
        print(
            json.dumps(
                {
                    "file": str(args.file),
                    "n_frames": recording.n_frames,
                    "first_frame": recording.first_frame,
                    "last_frame": last,
                    "rate_hz": recording.rate_hz,
                    "units_in_file": recording.units or None,
                    "units": "mm",
                    "labels": list(recording.labels),
                    "missing_samples": gaps,
                },
                indent=2,
            )
        )
        return 0
    rate = "no rate stated" if recording.rate_hz is None else f"{recording.rate_hz:g} Hz"
    print(
        f"{args.file}: {recording.n_frames} frames (numbered {recording.first_frame} to {last} "
        f"as in the file), {rate}, {len(recording.labels)} markers, "
        f"{f'units {recording.units}' if recording.units else 'no unit stated'} (read as mm)"
    )
    print(f"{'marker':<16}{'missing':>8}")
    for label, n in gaps.items():
        print(f"{label:<16}{n:>8}")
    return 0


def _labels(text: str | None) -> list[str] | None:
    if text is None:
        return None
    labels = [label.strip() for label in text.split(",") if label.strip()]
    if not labels:
        raise ValueError(f"no marker labels in {text!r}")
    return labels


#: The column of a joint centre's row holding the root of the trace of the covariance its
#: SD is read from (:meth:`jointbench.RecordingFit.stated_covariance`) [mm].
_STATED_COVARIANCE = "sqrt_trace_center_cov_mm"
#: The column of a row holding the root of the trace of the method's own covariance [mm], as
#: the pipeline's scores name it.
_OWN_COVARIANCE = "sqrt_trace_cov_mm"


def _row(fitted) -> dict:
    """One flat row of a fit for the CSV output (a failed method: its status, and no SD),
    its SD a number or ``None`` (:meth:`jointbench.RecordingFit.sd_fields`), and so the roots
    of the traces of the method's own covariance (:data:`_OWN_COVARIANCE`) and of the one the
    SD is read from (:data:`_STATED_COVARIANCE`)."""
    if isinstance(fitted, _Failed):
        return fitted.to_dict()
    row = {"method": fitted.method}
    result = fitted.result
    if fitted.kind == "axis":
        row.update(zip(("dir_x", "dir_y", "dir_z"), result.direction, strict=True))
        row.update(zip(("point_x_mm", "point_y_mm", "point_z_mm"), result.point, strict=True))
    else:
        row.update(zip(("x_mm", "y_mm", "z_mm"), result.center, strict=True))
    fields = fitted.sd_fields()
    row.update(fields)
    if fitted.kind == "axis":
        # The point's SD across the axis; its covariance has no flat column.
        row.update(point_precision(result))
        row.pop("point_covariance_mm2", None)
    # The method's own covariance under the name the pipeline's scores give it (paper C's W_c
    # for gauss-markov), and the one the SD is read from under the name of its diagnostic
    # (for gauss-markov-frame0 the method's own): None where the SD states no precision.
    names = {"own": _OWN_COVARIANCE, "stated": _STATED_COVARIANCE}
    for which, covariance in fitted.covariances(fields).items():
        row[names[which]] = None if covariance is None else float(np.sqrt(np.trace(covariance)))
    if fitted.bootstrap is not None:
        if fitted.kind == "axis":
            row["boot_cone95_deg"] = fitted.bootstrap_cone_deg()
        else:
            row["boot_sqrt_trace_cov_mm"] = float(np.sqrt(np.trace(fitted.bootstrap.covariance())))
        low, high = fitted.bootstrap.interval()[:, -3:]
        for axis, lo, hi in zip("xyz", low, high, strict=True):
            row[f"boot95_{axis}_mm"] = f"[{lo:.2f}, {hi:.2f}]"
    row.update(
        converged=bool(result.converged),
        status=result.status,
        frames=len(fitted.frames_used),
        gap_frames=fitted.n_gap_frames,
    )
    return row


def _readable(row: dict) -> dict:
    """A :func:`_row` for people: an SD that states no precision, and the roots of the
    covariances of its answer, read :data:`~jointbench.io.fit.NOT_DETERMINED`, in place of
    the flag that says so for programs."""
    readable = {key: value for key, value in row.items() if key != SD_STATED}
    for name in {*SD_NAMES.values(), _OWN_COVARIANCE, _STATED_COVARIANCE, "point_sd_mm"}:
        if name in readable and readable[name] is None:
            readable[name] = NOT_DETERMINED
    return readable


@dataclass(frozen=True)
class _Failed:
    """A method of ``--method all`` that could not fit the data, and why."""

    method: str
    error: str

    @property
    def status(self) -> str:
        return f"failed: {self.error}"

    def to_dict(self) -> dict:
        return {
            "method": self.method,
            "converged": False,
            SD_STATED: False,
            "status": self.status,
        }


def _fit_all(prepared, names: list[str], args: argparse.Namespace) -> list:
    """Each method's fit; with several methods, one that raises a ``ValueError`` (the input
    checks', or a failure the method states) becomes a :class:`_Failed`. A mistake in a
    method's code is a :class:`~jointbench.estimators.batching.ProgrammingError`, which stops
    the command whatever the methods."""
    fits = []
    for name in names:
        try:
            fits.append(
                prepared.fit(
                    name,
                    n_bootstrap=args.bootstrap,
                    block_length=args.block_length,
                    seed=args.seed,
                )
            )
        except ValueError as error:
            if len(names) == 1:
                raise
            prefix = f"{prepared.recording.source}: {prepared.kind} {name}: "
            fits.append(_Failed(name, str(error).removeprefix(prefix)))
    return fits


def _method_names(kind: str, method: str) -> list[str]:
    """The methods ``--method`` names for ``kind``: every registered one for ``all`` (the
    built-ins and those of the extensions loaded); an unknown name is a ``ValueError`` listing
    the known ones."""
    if method == "all":
        return list(jointbench.methods(kind))
    try:
        get(kind, method)
    except ValueError as error:
        raise ValueError(f"--method: {error}") from None
    return [method]


def _check_bootstrap_options(args: argparse.Namespace) -> None:
    """Refuse ``--bootstrap``, ``--block-length`` or ``--seed`` values no recording could take,
    naming the option: a ``ValueError`` from every method of ``--method all`` would otherwise
    be one failed row per method. A block longer than the frames is refused once they are
    known (:meth:`jointbench.io.Prepared.fit`)."""
    check_resampling(
        args.block_length or 1,  # the frames are not known yet: any block length fits
        args.bootstrap,
        args.block_length,
        args.seed,
        names=("--bootstrap", "--block-length", "--seed"),
        zero_is_none=True,
    )


def _check_writable(path: Path | None, option: str, source: Path) -> None:
    """``ValueError`` naming ``option`` and ``path`` (``None``: not asked for) when the output
    cannot be written there: a folder, in a folder that does not exist, without permission, or
    the file ``source``, the recording read, which it would overwrite. Checked before the fit,
    which may take minutes, and whose table would be lost with it."""
    if path is None:
        return
    if path.is_file() and source.is_file() and path.samefile(source):
        reason = "it is the recording read"
    elif path.is_dir():
        reason = "it is a folder"
    elif not path.parent.is_dir():
        reason = f"its folder {path.parent} does not exist"
    elif not os.access(path if path.exists() else path.parent, os.W_OK):
        reason = "no permission to write it"
    else:
        return
    raise ValueError(f"{option} {path}: cannot be written: {reason}")


def _fit(args: argparse.Namespace) -> int:
    # The config, the method name and the bootstrap's options first: a mistake in any stops
    # before the file is read.
    if args.configfile:
        _open_run(args)
    names = _method_names(args.kind, args.method)
    _check_bootstrap_options(args)
    _check_writable(args.world, "--world", args.file)
    recording = _read(args.file)
    moving = _labels(args.moving)
    reference = _labels(args.reference)
    if moving is None:
        if reference is not None:
            raise ValueError("name the moving segment's markers with --moving")
        moving = list(recording.labels)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        prepared = prepare(
            recording,
            args.kind,
            moving,
            reference,
            frames=args.frames,
            artefacts=args.artefacts,
            lab_fixed_reference=args.lab_fixed_reference,
        )
        fits = _fit_all(prepared, names, args)
    for warning in caught:
        print(f"jointbench: warning: {warning.message}", file=sys.stderr)
    done = [fitted for fitted in fits if not isinstance(fitted, _Failed)]
    for failed in fits:
        if isinstance(failed, _Failed):
            message = f"{args.file}: {failed.method} did not run: {failed.error}"
            print(f"jointbench: {message}", file=sys.stderr)
    code = 0 if done else 2
    if args.world is not None and done:
        _write_world(args.world, done)
    if args.format == "json":
        print(json.dumps([fitted.to_dict() for fitted in fits], indent=2))
        return code
    rows = [_row(fitted) for fitted in fits]
    if args.format == "csv":
        print(_table(rows).to_csv(index=False, float_format="%.9g"), end="")
        return code
    table = _table([_readable(row) for row in rows])
    print(table.to_string(index=False, float_format=lambda v: f"{v:.4f}"))
    if not done:
        return code
    frame = done[0].frame
    if frame is None:
        print("frame: as recorded (markers taken as already in the reference frame)")
    else:
        print(f"frame: technical frame of {', '.join(frame['segment'])}:")
        for key in ("origin", "x", "y", "z"):
            print(f"  {key}: {frame[key]}")
    if args.kind in CENTER_IS:
        print(f"x_mm, y_mm, z_mm: {CENTER_IS[args.kind]}")
    if done[0].anchor_frame is not None:
        print(f"anchor frame (both body frames coincide): {done[0].anchor_frame}")
    for fitted in done:
        stated = fitted.stated_covariance()
        if stated is not None:
            print(f"{_STATED_COVARIANCE}: {fitted.method}: from {stated[1]}")
    return code


def _table(rows: list[dict]) -> pd.DataFrame:
    """The fits' ``rows`` as one table: a row's missing entries, and ``None``, are empty in
    its CSV."""
    table = pd.DataFrame(rows)
    # A failed method's row has no counts; the others' stay whole numbers beside it.
    counts = [column for column in ("frames", "gap_frames") if column in table]
    table[counts] = table[counts].astype("Int64")
    return table


def _write_world(path: Path, fits: list) -> None:
    """Per frame and method, the centre (or axis point) in the lab frame [mm], as CSV."""
    tables = []
    for fitted in fits:
        world = fitted.world()
        table = pd.DataFrame(world, columns=["x_mm", "y_mm", "z_mm"])
        table.insert(0, "frame", np.arange(len(world)) + fitted.first_frame)
        table.insert(1, "method", fitted.method)
        tables.append(table)
    pd.concat(tables).to_csv(path, index=False, float_format="%.6f")
    print(f"wrote the world trajectory per frame to {path}", file=sys.stderr)


def _config_option(parser: argparse.ArgumentParser) -> None:
    """``--configfile``: the configs of a run, opened by :func:`_open_run`."""
    parser.add_argument(
        "--configfile",
        type=Path,
        action="append",
        default=[],
        help=f"a config over {DEFAULT_CONFIG}, as snakemake's --configfile (checked, then its "
        "extensions are loaded); may be repeated",
    )


def _run_options(parser: argparse.ArgumentParser) -> None:
    """The options of a command reading a run: its results folder and its configs."""
    parser.add_argument("--results", type=Path, default=Path("results"))
    _config_option(parser)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="jointbench",
        description="Functional joint centre and axis estimators, and the benchmark studies.",
        epilog=_method_list(),
        formatter_class=_Formatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {jointbench.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    inspect = sub.add_parser(
        "inspect",
        help="labels, frames, rate and missing samples of a C3D, TRC or CSV file",
        formatter_class=_Formatter,
    )
    inspect.add_argument("file", type=Path)
    inspect.add_argument("--format", choices=("table", "json"), default="table")
    inspect.set_defaults(run=_inspect)

    fit = sub.add_parser(
        "fit",
        help="fit a centre, an axis or a joint centre to a recording",
        description=(
            "Fit estimators to a recording (C3D, TRC, or CSV with columns frame,marker,x,y,z in "
            "mm). The answer is in the technical frame of the --reference markers (origin at "
            "their centroid, x from the first towards the second, z normal to the first three)."
            " Without --reference, the markers are taken as already in the reference frame."
            " With --configfile, the estimators of the run's extensions are fitted too, by name"
            " or with 'all' (the list below is of the built-in ones)."
        ),
        epilog=_method_list(),
        formatter_class=_Formatter,
    )
    fit.add_argument("file", type=Path)
    fit.add_argument("--kind", choices=KINDS, default="center", help="what to estimate")
    fit.add_argument("--reference", help="reference (proximal) segment's labels, comma-separated")
    fit.add_argument("--moving", help="moving (distal) segment's labels; default: every marker")
    fit.add_argument(
        "--frames",
        help="frame range start:stop in the file's frame numbers (as inspect shows them; stop "
        "excluded); a refused label swap names the ranges on each side",
    )
    fit.add_argument(
        "--method",
        default=None,
        help="a method name (see below; with --configfile, its extensions' too) or 'all' (a "
        "method that cannot fit the data gets a failed status; exit code 2 only if all fail); "
        "default per kind",
    )
    fit.add_argument("--format", choices=FORMATS, default="table")
    _config_option(fit)
    fit.add_argument(
        "--artefacts",
        choices=ARTEFACT_POLICIES,
        default="refuse",
        help="label swaps / markers falling off: refuse with a message, or leave out the frames "
        "that break the shape most frames share",
    )
    fit.add_argument(
        LAB_FIXED_FLAG,
        action="store_true",
        help="the --reference markers are fixed in the lab (a treadmill's frame, a force plate; "
        f"center and axis only): while the positions each holds (medians of {HELD_SAMPLES} "
        f"consecutive frames) stay within {LAB_FIXED_MM:g} mm of one another they are bounded "
        "by a capture volume, not by a body segment's "
        f"{MAX_SPAN_MM / 1000:g} m",
    )
    fit.add_argument(
        "--bootstrap", type=int, default=0, help="moving-block bootstrap resamples (0: none)"
    )
    fit.add_argument(
        "--block-length", type=int, default=None, help="bootstrap block [frames]; default sqrt(N)"
    )
    fit.add_argument("--seed", type=int, default=0, help="bootstrap seed")
    fit.add_argument(
        "--world",
        type=Path,
        help="also write the centre (or axis point) in the lab frame, per frame, to this CSV",
    )
    fit.set_defaults(run=_fit)

    snap = sub.add_parser(
        "snapshot",
        help="write the regression snapshot of tabulated means",
        formatter_class=_Formatter,
    )
    _run_options(snap)
    snap.add_argument("--output", type=Path, default=Path("tests/snapshots/summary.csv"))
    snap.set_defaults(run=_snapshot)

    readme = sub.add_parser(
        "readme",
        help="rewrite the README's generated blocks from the run's tables: the reproduction "
        "summary, the STA ranking, what stands out and the verdicts over seeds",
        description="Rewrite every block of the README between its <!-- NAME:start --> and "
        "<!-- NAME:end --> markers from the run's tables: the reproduction summary, the papers' "
        "headlines (the STA ranking), what stands out and the verdicts over seeds.",
        formatter_class=_Formatter,
    )
    _run_options(readme)
    readme.add_argument("--readme", type=Path, default=Path("README.md"))
    readme.set_defaults(run=_readme)

    compile_all = sub.add_parser(
        "precompile",
        help="compile every built-in method's kernels now (minutes of one core in a fresh "
        "install), so that later fits and jobs load them from the cache",
        description="Fit one small synthetic trial per built-in method and kind, by every path "
        "(checked and not, one trial and a batch), so that every compiled kernel is in Numba's "
        "cache beside the package: later processes load them. Run it once after installing, "
        "before many jobs start at once (a cluster run), which would each compile the same "
        "kernels.",
        formatter_class=_Formatter,
    )
    compile_all.set_defaults(run=_precompile)
    return parser


def _legacy(argv: list[str]) -> list[str]:
    """``fit KIND FILE`` (the earlier form) is ``fit FILE --kind KIND``."""
    if len(argv) >= 3 and argv[0] == "fit" and argv[1] in KINDS:
        return ["fit", argv[2], "--kind", argv[1], *argv[3:]]
    return argv


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(_legacy(list(sys.argv[1:] if argv is None else argv)))
    if args.command == "fit" and args.method is None:
        args.method = DEFAULT_METHODS[args.kind]
    try:
        code = args.run(args)
        sys.stdout.flush()  # a closed pipe shows here, not at the interpreter's exit
        return code
    except BrokenPipeError:
        # The reader of the output closed it (`| head`): it has what it wanted, and no error
        # is to be reported. What is still buffered goes nowhere, or it would fail at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (ValueError, OSError) as error:
        print(f"jointbench: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
