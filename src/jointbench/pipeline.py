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
import os
import platform
import sys
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import pandas as pd

from jointbench import machine
from jointbench.figures import extended
from jointbench.figures.common import save_figure
from jointbench.papers import (
    Inputs,
    Output,
    Paper,
    Table,
    get_paper,
    paper_names,
    papers_of_study,
    register_paper,
)
from jointbench.simulate import Study
from jointbench.study import config as jb_config
from jointbench.study.io import read_dataset, read_provenance, read_table
from jointbench.study.published import (
    comparison_rows,
    enforce_design,
    failure_message,
    load_published,
)
from jointbench.study.studies import get_study, register_study
from jointbench.study.summary import summarise
from jointbench.study.tables import markdown_table, write_tables

__all__ = [
    "caption_text",
    "check_published",
    "job",
    "load_extensions",
    "paper_labels",
    "paper_output",
    "provenance",
    "render_extended",
    "render_output",
    "run_metadata",
    "summarise_estimates",
    "write_captions",
    "write_front_page",
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


def paper_labels() -> dict[str, str]:
    """Each registered paper's label for summaries, by letter: ``"A (centre of rotation)"``."""
    labels = {}
    for key in paper_names():
        paper = get_paper(key)
        subject = paper.title.split(":", 1)[-1].strip()
        labels[paper.letter] = f"{paper.letter} ({subject})"
    return labels


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


# ----------------------------------------------------------------------------- report captions

EXTENDED_TABLE_CAPTION = (
    "Every {kind_name} estimator of the `{study}` study ({methods}), ranked by mean error in "
    "each condition on identical trials: mean and median error, trials converged and failed, "
    "rank. The note under the table says which are the paper's methods and which were added."
)
EXTENDED_FIGURE_CAPTION = (
    "Mean error of every estimator of the `{study}` study in every condition (log colour "
    "scale), and each estimator's mean rank over the conditions. † marks a cell where some "
    "trials failed or did not converge; a red outline marks the best of the condition, every "
    "tied method outlined."
)
COMPARISON_CAPTION = (
    "Every published value and claim of the papers beside ours, with the typed tolerance, the "
    "margin, the status and, for each value that does not reproduce, the recorded reason."
)
_KIND_NAMES = {
    "center": "centre-of-rotation",
    "axis": "axis-of-rotation",
    "joint_center": "joint-centre",
}


def caption_text(name: str, config: Mapping) -> str:
    """What the output called ``name`` shows (before its headline)."""
    if name == "published_comparison":
        return COMPARISON_CAPTION
    if name.startswith("extended_"):
        study = name.removeprefix("extended_").removesuffix("_figure")
        if name.endswith("_figure"):
            return EXTENDED_FIGURE_CAPTION.format(study=study)
        methods = ", ".join(jb_config.estimator_names(config, study))
        kind = _KIND_NAMES[get_study(study).kind]
        return EXTENDED_TABLE_CAPTION.format(kind_name=kind, study=study, methods=methods)
    return paper_output(name).caption


def paper_output(name: str) -> Output:
    """The registered paper output called ``name``; ``ValueError`` if no paper has it."""
    for key in paper_names():
        for output in get_paper(key).outputs:
            if output.name == name:
                return output
    raise ValueError(f"no paper has an output called {name!r}")


def _headline(name: str, tables: Mapping[str, pd.DataFrame]) -> str:
    if name == "published_comparison":
        counts = tables[name]["status"].value_counts()
        return (
            ", ".join(
                f"{counts.get(s, 0)} {s}"
                for s in ("reproduced", "not reproduced", "not applicable")
            )
            + "."
        )
    if name.startswith("extended_"):
        return extended.best_headline(tables[name.removesuffix("_figure")])
    output = paper_output(name)
    if output.headline is None:
        return ""
    return output.headline({source: tables[source] for source in output.summarises})


def write_captions(tables: Mapping[str, str], outputs: Sequence[str], config: Mapping) -> None:
    """One reStructuredText caption per output: what it shows, then its headline agreement."""
    loaded = {name: pd.read_csv(path) for name, path in tables.items()}
    for path in outputs:
        name = Path(path).stem
        headline = _headline(name, loaded)
        body = caption_text(name, config)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(f"{body}\n\n**Headline:** {headline}\n" if headline else f"{body}\n")


# ----------------------------------------------------------------------------- report front page

FRONT_INTRO = """\
jointbench: functional joint-parameter estimators, benchmarked
==============================================================

jointbench regenerates the figures and tables of three classic papers on functional joint
estimation from simulated motion-capture data with a known truth, ranks every estimator
(the papers' and any added) on identical trials, and checks every published value and claim
against what it reproduces, with a typed tolerance and its margin. Every number below is
generated from this run's results.
"""


def _rst_table(frame: pd.DataFrame, title: str) -> str:
    """``frame`` as an RST list-table (cells as text)."""
    lines = [f".. list-table:: {title}", "   :header-rows: 1", ""]
    for row in [list(frame.columns), *frame.astype(str).values.tolist()]:
        lines.append("   * - " + str(row[0]))
        lines += [f"     - {cell}" for cell in row[1:]]
    return "\n".join(lines) + "\n"


def _summary_frame(comparison: pd.DataFrame) -> pd.DataFrame:
    labels = paper_labels()
    rows = []
    for paper, part in comparison.groupby("paper", sort=True):
        row = {"paper": labels.get(paper, paper)}
        for entry, column in (("value", "published values"), ("claim", "claims")):
            tested = part[(part["entry"] == entry) & (part["status"] != "not applicable")]
            row[column] = f"{int((tested['status'] == 'reproduced').sum())} / {len(tested)}"
        row["not comparable"] = int((part["status"] == "not applicable").sum())
        rows.append(row)
    return pd.DataFrame(rows)


def _rankings(tables: Mapping[str, pd.DataFrame]) -> list[str]:
    lines = []
    for name, table in sorted(tables.items()):
        if not name.startswith("extended_"):
            continue
        ranks = extended.mean_ranks(table)
        leaders = ", ".join(
            f"{row.method} (mean rank {row.mean_rank:.2f})" for row in ranks.head(3).itertuples()
        )
        lines.append(f"- study ``{name.removeprefix('extended_')}``: {leaders}")
    return lines


def run_metadata() -> dict[str, str]:
    """The machine and software versions of this run, for the report beside the timings."""
    versions = {name: importlib.metadata.version(name) for name in _VERSIONED}
    return {
        "machine": f"{platform.system()} {platform.machine()}, {os.cpu_count()} logical CPUs",
        "processor": machine.processor(),
        "python": platform.python_version(),
        **versions,
    }


_VERSIONED = ("jointbench", "numpy", "scipy", "pandas", "matplotlib", "snakemake")


def write_front_page(
    tables: Mapping[str, str], collected: Sequence[str], path: str, config: Mapping
) -> None:
    """The report's landing page: the benchmark, its headline findings, the provenance of every
    estimator's results and the run's machine."""
    loaded = {name: pd.read_csv(p) for name, p in tables.items()}
    parts = [FRONT_INTRO]
    comparison = loaded.get("published_comparison")
    if comparison is not None and not comparison.empty:
        parts += [
            "Reproduction summary\n--------------------\n",
            _rst_table(_summary_frame(comparison), "published values and claims reproduced"),
            "Every value and claim, with the paper's sentence, the criterion, the margin and the "
            "reason for each deviation, is under *Agreement with the papers*.\n",
        ]
    rankings = _rankings(loaded)
    if rankings:
        parts += ["Rankings\n--------\n", "\n".join(rankings) + "\n"]
    if "paper_c_calibration" in loaded:
        calibration = loaded["paper_c_calibration"][
            ["method", "n_frames", "trials", "inside_95", "calibrated"]
        ]
        parts += [
            "Calibration of the predicted covariance\n---------------------------------------\n",
            _rst_table(
                calibration, "share of trials whose true centre is inside the 95 % ellipsoid"
            ),
        ]
    provenance_rows = [
        {
            "study": Path(path).stem,
            "estimator": method,
            "code fingerprint": record.get("code", "") or "(external rule)",
            "jointbench": record.get("jointbench", ""),
        }
        for path in collected
        for method, record in read_provenance(path).get("estimators", {}).items()
    ]
    if provenance_rows:
        parts += [
            "Provenance\n----------\n",
            "Each estimates file records the fingerprint of the code that produced it "
            "(``jointbench.fingerprint``); editing an estimator changes its fingerprint and "
            "reruns its jobs only.\n",
            _rst_table(pd.DataFrame(provenance_rows), "the code behind each estimator's results"),
        ]
    metadata = pd.DataFrame(list(run_metadata().items()), columns=["", "this run"])
    parts += [
        "This run\n--------\n",
        "Timings in the tables were measured inside the jobs of this run, on this machine:\n",
        _rst_table(metadata, "machine and software"),
    ]
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text("\n".join(parts))
