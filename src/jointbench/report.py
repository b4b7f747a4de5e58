"""The report's texts: each output's caption with its generated headline, and the landing page
(what the benchmark is, its headline findings, provenance, and the run's machine)."""

from __future__ import annotations

import importlib.metadata
import os
import platform
from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from jointbench import machine
from jointbench.figures import extended
from jointbench.papers import Output, get_paper, paper_labels, paper_names
from jointbench.study import config as jb_config
from jointbench.study.io import read_provenance
from jointbench.study.snapshot import reproduction_counts
from jointbench.study.studies import get_study

__all__ = [
    "caption_text",
    "paper_output",
    "run_metadata",
    "write_captions",
    "write_front_page",
]


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
            _rst_table(
                reproduction_counts(comparison, paper_labels()),
                "published values and claims reproduced",
            ),
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
            "(``jointbench.fingerprint``: its job's script and every module of the package "
            "the script can import); an edit of any of them reruns the job.\n",
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
