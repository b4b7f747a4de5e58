"""What the workflow's jobs do, over the library: the scripts in ``workflow/scripts`` are thin
calls into this module.

It sits on top of every other layer: it reads files, asks the study and paper registries, renders
outputs and writes them. Extensions (a study or paper outside the package, listed under
``extensions`` in the config) are imported here, so the rules and the jobs see the same
registries.
"""

from __future__ import annotations

import contextlib
import importlib.metadata
import importlib.util
import logging
import sys
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import pandas as pd

from jointbench.figures import extended
from jointbench.figures.common import save_figure
from jointbench.papers import (
    Inputs,
    Paper,
    Table,
    get_paper,
    papers_of_study,
    register_paper,
)
from jointbench.simulate import Study
from jointbench.study.io import read_dataset, read_table
from jointbench.study.published import (
    comparison_rows,
    enforce_design,
    failure_message,
    load_published,
)
from jointbench.study.studies import register_study
from jointbench.study.summary import summarise
from jointbench.study.tables import markdown_table, write_tables

__all__ = [
    "check_published",
    "job",
    "load_extensions",
    "provenance",
    "render_extended",
    "render_output",
    "summarise_estimates",
]

log = logging.getLogger("jointbench")


def load_extensions(config: Mapping, base: str | Path = ".") -> None:
    """Import every file under ``extensions`` and register the ``Study`` and ``Paper`` values
    it defines. Importing the same file again is a no-op."""
    for entry in config.get("extensions", []):
        path = (Path(base) / entry).resolve()
        if not path.is_file():
            raise ValueError(f"config error at extensions: {entry!r} is not a file ({path})")
        name = f"jointbench_extension_{path.stem}"
        module = sys.modules.get(name)
        if module is None or Path(module.__file__).resolve() != path:
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
        for value in vars(module).values():
            if isinstance(value, Study):
                register_study(value)
            elif isinstance(value, Paper):
                register_paper(value)


@contextlib.contextmanager
def job(snakemake) -> Iterator[None]:
    """Run one Snakemake job's work: extensions loaded, messages and any error written to the
    job's log (the file Snakemake points to when the job fails)."""
    handlers = []
    for path in list(snakemake.log):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        handler = logging.FileHandler(path, mode="w")
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
        handlers.append(handler)
        log.addHandler(handler)
    log.setLevel(logging.INFO)
    try:
        load_extensions(snakemake.config)
        log.info(
            "rule %s: %d input(s) -> %d output(s)",
            snakemake.rule,
            len(snakemake.input),
            len(snakemake.output),
        )
        yield
        log.info("done")
    except Exception:
        log.exception("rule %s failed", snakemake.rule)
        raise
    finally:
        for handler in handlers:
            log.removeHandler(handler)
            handler.close()


def provenance(snakemake) -> dict[str, object]:
    """What a job's files record of how they were made: the package version, the rule, the
    fingerprint of the code it ran, and the config values its study depends on."""
    study = getattr(snakemake.params, "study", None) or snakemake.wildcards.get("study")
    settings = snakemake.config.get("studies", {}).get(study, {}) if study else {}
    return {
        "jointbench": importlib.metadata.version("jointbench"),
        "rule": snakemake.rule,
        "code": getattr(snakemake.params, "code", ""),
        "config": {"base_seed": snakemake.config.get("base_seed"), "study": settings},
    }


def _inputs(paper: Paper, collected: str, datasets: Sequence[str], config: Mapping) -> Inputs:
    return Inputs(
        collected=read_table(collected),
        published=load_published(paper.published),
        config=config,
        datasets=[read_dataset(path) for path in datasets],
    )


def render_output(
    paper_key: str,
    output_name: str,
    collected: str,
    datasets: Sequence[str],
    outputs,
    config: Mapping,
) -> None:
    """Render one paper output from its input files into ``outputs`` (png/pdf or csv/md)."""
    paper = get_paper(paper_key)
    output = paper.output(output_name)
    result = output.render(_inputs(paper, collected, datasets, config))
    if isinstance(result, Table):
        write_tables(result.frame, outputs, title=result.title, note=result.note)
    else:
        save_figure(result, outputs)
    log.info("%s written", output_name)


def _paper_methods(study: str) -> extended.PaperMethods:
    papers = papers_of_study(study)
    if not papers:
        return extended.NO_PAPER
    return papers[0].letter, papers[0].methods


def render_extended(study: str, collected: str, outputs, config: Mapping, *, what: str) -> None:
    """The extended ranking of ``study``: ``what`` is ``"table"`` or ``"figure"``."""
    frame = read_table(collected)
    paper = _paper_methods(study)
    if what == "figure":
        save_figure(extended.extended_figure(frame, study, paper), outputs)
        return
    table = extended.extended_table(frame, study, paper)
    methods = list(extended.mean_ranks(table)["method"])
    note = (
        f"{extended.origin_note(study, methods, paper, config)} rank: 1 = lowest mean error of "
        f"the condition (means equal to {extended.TIE_DIGITS} significant digits share a rank; a "
        "method without a finite error ranks last); best: rank 1 with a finite mean. Means and "
        "medians leave out failed trials (no finite error), counted in failed."
    )
    write_tables(
        table,
        outputs,
        title=f"Extended ranking, study {study}: every estimator on every condition",
        note=note,
    )


def summarise_estimates(study: str, paths: Sequence[str], output: str) -> None:
    """One estimator's mean and median error per condition, from its estimates files."""
    estimates = pd.concat([read_table(path) for path in paths], ignore_index=True)
    summarise(estimates, study).to_csv(output, index=False)


def comparison(collected: Mapping[str, str], config: Mapping) -> pd.DataFrame:
    """Every published value and claim of every paper whose study ran, beside ours.

    ``collected`` maps study names to their collected results files.
    """
    frames = []
    for study, path in collected.items():
        frame = read_table(path)
        for paper in papers_of_study(study):
            document = load_published(paper.published)
            inputs = Inputs(collected=frame, published=document, config=config)
            rows = comparison_rows(document, paper.measure(inputs))
            frames.append(enforce_design(rows, document, config))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def check_published(collected: Mapping[str, str], outputs, config: Mapping) -> pd.DataFrame:
    """Write ``published_comparison.{csv,md}``; raise ``ValueError`` naming every value that no
    longer reproduces without a recorded reason."""
    table = comparison(collected, config)
    counts = table.groupby(["study", "status"]).size().unstack(fill_value=0).reset_index()
    write_tables(
        table,
        outputs,
        title="Published values and claims beside ours",
        note="margin: how far inside (+) or outside (−) its tolerance each value lies, in the "
        "tolerance's own units.\n\n## Counts by study and status\n\n" + markdown_table(counts),
    )
    message = failure_message(table)
    if message:
        raise ValueError(message)
    return table
