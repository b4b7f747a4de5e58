"""What the jobs that render and check the papers do: a paper output, the extended ranking and
the published-value check, each from the collected results to its files.

It sits on top of every other layer: it reads files, asks the study and paper registries, renders
outputs and writes them. Its scripts run it inside :func:`jointbench.jobs.job`; the jobs that
simulate, estimate, collect and summarise call :mod:`jointbench.running.run` and do not import it.
matplotlib is imported only when a figure is drawn (:func:`jointbench.figures.common.pyplot`), so
the table jobs and the check run without it.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from jointbench.comparison.published import (
    COLUMNS,
    comparison_rows,
    enforce_design,
    failure_message,
    load_published,
    reader_order,
    run_basis,
    status_legend,
)
from jointbench.configuration.config import condition_id
from jointbench.figures import extended
from jointbench.figures.common import save_figure
from jointbench.papers import Inputs, Table, get_paper, papers_of_study
from jointbench.resultfiles.parquet import read_dataset, read_table
from jointbench.resultfiles.tables import markdown_table, write_tables
from jointbench.running.collected import require_results

__all__ = [
    "OUTPUT_SEPARATOR",
    "check_published",
    "extended_name",
    "render_extended",
    "render_study",
]

log = logging.getLogger(__name__)


#: Joins an output's name and a file kind in the output keys of a study's render job
#: (``paper_a_fig3__png``, ``extended_cmc__csv``): one job writes every output of its study.
OUTPUT_SEPARATOR = "__"


def extended_name(study: str) -> str:
    """The output name of a study's extended ranking (table; its figure adds ``_figure``)."""
    return f"extended_{study}"


def _files(outputs: Mapping[str, str], name: str) -> dict[str, str]:
    """The files of output ``name`` in a render job's outputs, by kind (png, pdf, csv, ...)."""
    prefix = f"{name}{OUTPUT_SEPARATOR}"
    return {key[len(prefix) :]: path for key, path in outputs.items() if key.startswith(prefix)}


def render_study(
    study: str,
    paper_outputs: Mapping[str, Sequence[str]],
    collected: str,
    datasets: Sequence[str],
    outputs: Mapping[str, str],
    config: Mapping,
) -> None:
    """Render, from one reading of the study's collected results and of each dataset, the
    outputs ``paper_outputs`` names (paper key -> output names) and the study's extended
    ranking; ``outputs`` maps ``<output name>__<kind>`` to a path (png/pdf or csv/md/html).

    ``ValueError`` naming the study when every trial failed, or every trial of a method its
    papers compare (see :func:`jointbench.running.collected.require_results`): nothing is drawn
    from nothing."""
    frame = read_table(collected)
    require_results(frame, study, collected, _methods_compared(study))
    # Dataset files are named by their condition (configuration.config.condition_id).
    by_condition = {Path(path).stem: read_dataset(path) for path in datasets}
    for key, names in paper_outputs.items():
        paper = get_paper(key)
        inputs = Inputs(
            collected=frame,
            published=load_published(paper.published, paper.declares, paper.tables),
            config=config,
        )
        for name in names:
            output = paper.output(name)
            drawn = [by_condition[condition_id(c)] for c in output.conditions]
            result = output.render(dataclasses.replace(inputs, datasets=drawn))
            files = _files(outputs, name)
            if isinstance(result, Table):
                write_tables(
                    result.frame,
                    files,
                    title=result.title,
                    note=result.note,
                    headers=result.headers,
                )
            else:
                save_figure(result, files)
            log.info("%s written", name)
    files = _files(outputs, extended_name(study))
    for what in ("table", "figure"):
        _render_extended(study, frame, files, config, what=what)
    log.info("%s written", extended_name(study))


def _methods_compared(study: str) -> list[str]:
    """The methods the papers of ``study`` compare, each once."""
    return list(dict.fromkeys(m for paper in papers_of_study(study) for m in paper.methods))


def _paper_methods(study: str) -> extended.PaperMethods:
    papers = papers_of_study(study)
    if not papers:
        return extended.NO_PAPER
    return papers[0].letter, papers[0].methods


def render_extended(study: str, collected: str, outputs, config: Mapping, *, what: str) -> None:
    """The extended ranking of ``study`` from its collected results file: ``what`` is
    ``"table"`` (``outputs``: csv, md, html) or ``"figure"`` (png, pdf)."""
    _render_extended(study, read_table(collected), outputs, config, what=what)


def _render_extended(study: str, frame: pd.DataFrame, outputs, config: Mapping, *, what: str):
    paper = _paper_methods(study)
    if what == "figure":
        save_figure(extended.extended_figure(frame, study, paper), outputs)
        return
    table = extended.extended_table(frame, study, paper)
    methods = list(extended.mean_ranks(table)["method"])
    note = (
        f"{extended.origin_note(study, methods, paper, config)} rank: within the condition, "
        "fewest failed trials first, then lowest common mean error: the mean over the "
        "common_trials that every method with as many failed trials answered, so that those "
        "methods are compared on identical trials and one that gives up on hard trials does "
        "not win on the easy ones (means equal to "
        f"{extended.TIE_DIGITS} significant digits share a rank; a method without a finite error "
        "ranks last among those with as many failures; where such methods have no trial in "
        "common, common_trials is 0 and each one's own mean ranks it); best: rank 1 with a "
        "finite mean. Means and medians leave out failed trials (no finite error), counted in "
        "failed."
    )
    write_tables(
        table,
        outputs,
        title=f"Extended ranking, study {study}: every estimator on every condition",
        note=note,
    )


def comparison(collected: Mapping[str, str], config: Mapping) -> pd.DataFrame:
    """Every published value and claim of every paper whose study ran, beside ours.

    ``collected`` maps study names to their collected results files; a study none of whose
    trials has a finite error, or with a compared method none of whose trials has one, is
    refused by name, not judged (:func:`jointbench.running.collected.require_results`).
    """
    frames = []
    for study, path in collected.items():
        frame = read_table(path)
        require_results(frame, study, path, _methods_compared(study))
        for paper in papers_of_study(study):
            document = load_published(paper.published, paper.declares, paper.tables)
            inputs = Inputs(collected=frame, published=document, config=config)
            rows = comparison_rows(document, paper.measure(inputs))
            frames.append(enforce_design(rows, document, config))
    # A run of no study with a paper has no row, but the columns every reader of it reads.
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=COLUMNS)


def check_published(collected: Mapping[str, str], outputs, config: Mapping) -> pd.DataFrame:
    """Write ``published_comparison.{csv,md}``; raise ``ValueError`` naming every value that no
    longer reproduces without a recorded reason."""
    table = reader_order(comparison(collected, config))
    counts = table.groupby(["study", "status"]).size().unstack(fill_value=0).reset_index()
    write_tables(
        table,
        outputs,
        title="Published values and claims beside ours",
        note="Claims with a verdict first, then values with a verdict, then the rows without "
        f"one. {status_legend()}. {run_basis(config, sorted(set(table['study'])))}. Margin: how "
        "far inside or outside its tolerance each value lies, in the tolerance's own "
        "units.\n\n## Counts by study and status\n\n" + markdown_table(counts),
    )
    message = failure_message(table)
    if message:
        raise ValueError(message)
    return table
