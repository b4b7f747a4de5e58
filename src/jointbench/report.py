"""The report's texts: each output's caption with its generated headline, the page that shows an
output beside its caption, the landing page (what the benchmark is, its findings in sentences,
provenance, and the run's machine) and the finishing touches on Snakemake's HTML."""

from __future__ import annotations

import base64
import html
import importlib.metadata
import os
import platform
import re
import shlex
import subprocess
import sys
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path

import pandas as pd

from jointbench import invocation, machine
from jointbench.comparison.snapshot import reproduction_counts
from jointbench.configuration import config as jb_config
from jointbench.configuration.studies import get_study
from jointbench.figures import extended
from jointbench.figures.common import study_title
from jointbench.papers import Output, get_paper, paper_labels, paper_names, papers_of_study
from jointbench.resultfiles.parquet import read_provenance

__all__ = [
    "GLOSSARY",
    "REPORT_TITLE",
    "caption_text",
    "check_current",
    "closing_lines",
    "findings",
    "finish_report",
    "front_intro",
    "jobs_named",
    "output_label",
    "output_page",
    "output_title",
    "paper_output",
    "pending_jobs",
    "run_metadata",
    "write_captions",
    "write_front_page",
    "write_pages",
]


EXTENDED_TABLE_CAPTION = (
    "Every {kind_name} estimator of the {study} study ({methods}), ranked in each condition "
    "by failed trials, then by mean error over the trials that every method with as many "
    "failures answered (identical trials; each method's own mean where they share none): mean "
    "and median error, trials converged and failed, the common trials and their mean, rank. "
    "The note under the table says which are the paper's methods and which were added."
)
EXTENDED_FIGURE_CAPTION = (
    "Mean error of every estimator of the {study} study in every condition (log colour "
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
            return EXTENDED_FIGURE_CAPTION.format(study=study_title(study))
        methods = ", ".join(jb_config.estimator_names(config, study))
        kind = _KIND_NAMES[get_study(study).kind]
        return EXTENDED_TABLE_CAPTION.format(
            kind_name=kind, study=study_title(study), methods=methods
        )
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


def readme_headlines(tables_dir: str | Path, blocks: Collection[str]) -> dict[str, str]:
    """Per paper output marked ``in_readme`` whose block is among the README's ``blocks``: its
    headline, from its tables' CSV files in ``tables_dir`` (``ValueError`` naming a missing
    one: the run did not make it)."""
    out = {}
    for key in paper_names():
        for output in get_paper(key).outputs:
            if not output.in_readme or output.name not in blocks:
                continue
            tables = {}
            for source in output.summarises:
                path = Path(tables_dir) / f"{source}.csv"
                if not path.is_file():
                    raise ValueError(f"{path}: missing; the README's {output.name} needs it")
                tables[source] = pd.read_csv(path)
            out[output.name] = _headline(output.name, tables)
    return out


def write_captions(tables: Mapping[str, str], outputs: Sequence[str], config: Mapping) -> None:
    """One reStructuredText caption per output: what it shows, then its headline agreement."""
    loaded = {name: pd.read_csv(path) for name, path in tables.items()}
    for path in outputs:
        name = Path(path).stem
        headline = _headline(name, loaded)
        body = caption_text(name, config)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(f"{body}\n\n**Headline:** {headline}\n" if headline else f"{body}\n")


# ----------------------------------------------------------------------------- output pages

#: The report's name: its browser tab and the landing page's title.
REPORT_TITLE = "jointbench: functional joint centre and axis estimators, benchmarked"
#: The report file the closing lines and the README name.
REPORT_FILE = "results/report.html"


def output_label(name: str) -> str:
    """How an output is listed in the report's menu: "Fig 3", "Table 1", "Claims",
    "Extended ranking (figure)", "Every value and claim"."""
    if name == "published_comparison":
        return "Every value and claim"
    if name.startswith("extended_"):
        return "Extended ranking" + (" (figure)" if name.endswith("_figure") else " (table)")
    stem = re.sub(r"^paper_[a-z]+_", "", name)
    match = re.fullmatch(r"(fig|table)(\d+)", stem)
    if match:
        return f"{match[1].capitalize()} {match[2]}"
    return stem.replace("_", " ").capitalize()


def output_title(name: str) -> str:
    """An output's title on its page: "Paper A Fig 3", "Extended ranking (figure): thumb CMC"."""
    if name == "published_comparison":
        return "Agreement with the papers: every value and claim"
    if name.startswith("extended_"):
        study = name.removeprefix("extended_").removesuffix("_figure")
        return f"{output_label(name)}: {study_title(study)}"
    key = re.match(r"paper_[a-z]+", name)
    if key and key[0] in paper_names():
        return f"Paper {get_paper(key[0]).letter} {output_label(name)}"
    return output_label(name)


_PAGE_STYLE = (
    "body{font-family:sans-serif;font-size:14px;margin:0;padding:12px;color:#222}"
    ".page{display:flex;flex-wrap:wrap;gap:16px;align-items:flex-start}"
    ".caption{flex:1 1 18em;max-width:30em;line-height:1.45}"
    ".caption h2{font-size:17px;margin:0 0 8px}"
    ".shown{flex:1000 1 42em;min-width:0}"
    ".shown img{width:100%;height:auto;display:block}"
    ".shown table{border-collapse:collapse;font-size:13px}"
    ".shown th,.shown td{padding:3px 8px;border-bottom:1px solid #ddd;text-align:left;"
    "vertical-align:top}.shown th{background:#f3f3f3;position:sticky;top:0}"
    ".file{color:#666;font-size:12px}"
)


def _caption_html(rst: str) -> str:
    from docutils.core import publish_parts
    from docutils.writers import get_writer_class

    # A writer object, which every docutils Snakemake admits takes: its name as ``writer_name``
    # is deprecated from 0.22 on, and as ``writer`` is refused before it.
    return publish_parts(rst, writer=get_writer_class("html")())["body"]


def _body(table_html: str) -> str:
    """What is between ``<body>`` and ``</body>`` of a table page, its style left behind."""
    match = re.search(r"<body>(.*)</body>", table_html, flags=re.S)
    return match[1] if match else table_html


def output_page(title: str, caption_rst: str, shown: str | Path) -> str:
    """A self-contained HTML page of one output beside its caption: a PNG figure (embedded)
    or a table page's body. The caption sits to the right of the output on a wide window and
    above it on a narrow one, so a figure and what it shows are on screen together."""
    path = Path(shown)
    if path.suffix == ".png":
        data = base64.b64encode(path.read_bytes()).decode()
        content = f"<img alt='{html.escape(title)}' src='data:image/png;base64,{data}'>"
    else:
        content = _body(path.read_text())
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title><style>{_PAGE_STYLE}</style></head><body>"
        "<div class='page'><div class='shown'>"
        f"{content}</div><div class='caption'><h2>{html.escape(title)}</h2>"
        f"{_caption_html(caption_rst)}<p class='file'>File: {html.escape(str(path))}</p>"
        "</div></div></body></html>\n"
    )


def write_pages(
    shown: Mapping[str, str],
    captions: Mapping[str, str],
    titles: Mapping[str, str],
    pages: Sequence[str],
) -> None:
    """One :func:`output_page` per page path; its stem names the output in ``shown`` (the file
    it shows), ``captions`` (its caption file) and ``titles``."""
    for page in pages:
        name = Path(page).stem
        text = output_page(titles[name], Path(captions[name]).read_text(), shown[name])
        Path(page).parent.mkdir(parents=True, exist_ok=True)
        Path(page).write_text(text)


# ----------------------------------------------------------------------------- report front page


def front_intro() -> str:
    """The landing page's opening: what the benchmark is, naming the registered papers."""
    papers = [get_paper(key) for key in paper_names()]
    named = "; ".join(f"{p.letter}: {p.citation}" for p in papers)
    return f"""\
{REPORT_TITLE}
{"=" * len(REPORT_TITLE)}

jointbench regenerates the figures and tables of {len(papers)} papers on functional joint
estimation ({named}) from simulated motion capture with a known truth, ranks every estimator
(the papers' and any added) on identical trials, and checks every published value and claim
against this run with a stated tolerance. Every number on this page is generated from this run.
"""


#: Every abbreviation the report uses, defined once.
GLOSSARY = {
    "CoR / AoR": "centre / axis of rotation",
    "CMC, MCP": "thumb carpometacarpal joint, index metacarpophalangeal joint",
    "RoM; FE, AA": "range of motion; flexion–extension, abduction–adduction",
    "NM, LS, BC, MA, IS": "paper A's five centre fits (Chang & Pollard's names; see README)",
    "planar, radial, combined": "paper B's three axis costs",
    "GM, GM-f0": "gauss-markov (paper C's method) and gauss-markov-frame0 (ours, which also "
    "models the noise of the frame-0 poses)",
    "SCoRE, SARA, LM": "added estimators: symmetrical centre and axis of rotation "
    "estimation (Ehrig et al.), and paper A's sphere fit by Levenberg–Marquardt",
    "Nt": "the number of frames a hip estimate uses",
}


def _count(part: pd.DataFrame, entry: str) -> tuple[int, int, int]:
    """``(reproduced, tested, shown only)`` of the ``entry`` rows (value or claim)."""
    rows = part[part["entry"] == entry]
    tested = rows[rows["status"] != "not applicable"]
    return (
        int((tested["status"] == "reproduced").sum()),
        len(tested),
        len(rows) - len(tested),
    )


def _values_sentence(reproduced: int, tested: int, shown: int) -> str:
    if tested:
        text = f"{reproduced} of {tested} published values within tolerance"
        return text + (f" ({shown} more shown beside ours)" if shown else "")
    if shown:
        return f"its {shown} published values are shown beside ours, none comparable as a test"
    return "no published values"


def findings(tables: Mapping[str, pd.DataFrame]) -> list[str]:
    """One sentence per paper (claims and values reproduced, who ranks best on its study, and
    what the paper itself adds, :attr:`Paper.front_page`), generated from the run's tables."""
    comparison = tables.get("published_comparison")
    lines = []
    for key in paper_names():
        paper = get_paper(key)
        text = f"**{paper.title}** (study {study_title(paper.study)})"
        if comparison is not None:
            part = comparison[comparison["paper"] == paper.letter]
            if part.empty:
                continue
            claims_ok, claims, _ = _count(part, "claim")
            text += f": {claims_ok} of {claims} claims reproduced; " + _values_sentence(
                *_count(part, "value")
            )
        ranking = tables.get(f"extended_{paper.study}")
        if ranking is not None and papers_of_study(paper.study)[0] is paper:
            text += "; " + extended.best_headline(ranking).rstrip(".")
        sentence = paper.front_page(tables).finding if paper.front_page else ""
        if sentence:
            text += ". " + sentence[:1].upper() + sentence[1:]
        lines.append("- " + text.rstrip(".") + ".")
    return lines


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
        lines.append(f"- {study_title(name.removeprefix('extended_'))}: {leaders}")
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
    parts = [front_intro(), "Findings\n--------\n", "\n".join(findings(loaded)) + "\n"]
    parts += [
        "Each paper's figures and tables are in the menu on the left, each beside its caption; "
        "*Agreement with the papers* has every value and claim with the paper's sentence.\n",
        "Abbreviations: " + "; ".join(f"**{k}** {v}" for k, v in GLOSSARY.items()) + ".\n",
    ]
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
    for key in paper_names():
        paper = get_paper(key)
        for heading, title, frame in paper.front_page(loaded).sections if paper.front_page else ():
            parts += [f"{heading}\n{'-' * len(heading)}\n", _rst_table(frame, title)]
    provenance_rows = [
        {
            "study": study_title(Path(path).stem),
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


# ----------------------------------------------------------------------------- finishing

# Snakemake's template centres its landing pane vertically in a pane as tall as the window, so a
# landing page taller than the window starts above the top, out of reach; it also narrows the
# description to a column. These rules put the pane's top at the top and widen the text.
REPORT_STYLE = """
div.grow.h-screen.overflow-auto { align-items: flex-start !important; }
div.prose.max-w-lg { max-width: 64rem !important; }
"""


def finish_report(path: str | Path) -> bool:
    """Give the HTML report Snakemake wrote at ``path`` its name (the tab title, not "Snakemake
    Report") and :data:`REPORT_STYLE`; ``False`` if there is no such HTML file. Idempotent."""
    path = Path(path)
    if path.suffix != ".html" or not path.is_file():
        return False
    text = path.read_text(errors="surrogateescape")
    text = re.sub(
        r"<title>.*?</title>", f"<title>{html.escape(REPORT_TITLE)}</title>", text, count=1
    )
    style = f"<style id='jointbench-style'>{REPORT_STYLE}</style>"
    if "id='jointbench-style'" not in text:
        text = text.replace("</head>", style + "</head>", 1)
    path.write_text(text, errors="surrogateescape")
    return True


def _option(argv: Sequence[str], names: Sequence[str], default: str) -> str | None:
    """The value of a command-line option called any of ``names`` (``default`` when it is
    given without one); ``None`` when it is absent."""
    for index, argument in enumerate(argv):
        for name in names:
            if argument.startswith(f"{name}="):
                return argument.split("=", 1)[1]
            if argument == name:
                following = argv[index + 1] if index + 1 < len(argv) else ""
                return following if following and not following.startswith("-") else default
    return None


def report_path(argv: Sequence[str]) -> str | None:
    """The file a ``snakemake --report [FILE]`` command line writes (Snakemake's default
    ``report.html`` when none is given), inside ``--directory`` when one is given (Snakemake
    writes it there); ``None`` for any other command."""
    path = _option(argv, ["--report"], "report.html")
    if path is None:
        return None
    directory = _option(argv, ["--directory", "-d"], ".")
    return str(Path(directory or ".", path))


def pending_jobs(dry_run_output: str) -> dict[str, int]:
    """How many jobs of each rule a Snakemake dry run's output lists in its first "Job stats"
    table, the default target's rule (``all``) and the total left out; empty when it has
    nothing to do."""
    _, found, table = dry_run_output.partition("Job stats:")
    counts = {}
    # A header, its underline, then one "rule count" row per rule down to the total.
    for line in table.splitlines()[3:] if found else []:
        row = re.fullmatch(r"(\S+)\s+(\d+)", line.strip())
        if row is None or row.group(1) == "total":
            break
        counts[row.group(1)] = int(row.group(2))
    counts.pop("all", None)
    return counts


def jobs_named(pending: Mapping[str, int]) -> str:
    """The jobs ``pending`` (:func:`pending_jobs`) as a refusal names them: ``rule (count)``,
    comma-separated, in the dry run's order."""
    return ", ".join(f"{rule} ({count})" for rule, count in pending.items())


def dry_run_pending(
    command: Sequence[str],
    what: str,
    run: Callable[..., subprocess.CompletedProcess] = subprocess.run,
) -> dict[str, int]:
    """:func:`pending_jobs` of the Snakemake dry run ``command``, which ``what`` (the command
    asking) runs to learn whether the results it reads are up to date; ``ValueError`` with the
    dry run's output where it fails."""
    return pending_jobs(
        _output(command, what, "the dry run that checks the results are up to date", run)
    )


def _output(
    command: Sequence[str],
    what: str,
    asked: str,
    run: Callable[..., subprocess.CompletedProcess],
) -> str:
    """The standard output of the Snakemake ``command``, ``asked`` by ``what`` (the command
    asking); ``ValueError`` naming both, with the command's output, where it fails."""
    done = run(list(command), capture_output=True, text=True)
    if done.returncode != 0:
        raise ValueError(f"{what}: {asked} failed:\n" + (done.stdout + done.stderr).strip()[-3000:])
    return done.stdout


def check_current(
    argv: Sequence[str], run: Callable[..., subprocess.CompletedProcess] = subprocess.run
) -> None:
    """Stop a ``snakemake --report`` command line (``argv``, ``sys.argv``) whose run's results
    are not up to date with the code, config and data that make them: a report of them would
    show what an edit, or a run that failed, left behind. By the same program and interpreter
    with the options that choose the workflow and its config
    (:func:`jointbench.invocation.workflow_options`): a dry run of the run's default target
    says what a run would redo, and its summary which files of the run are missing, such as
    a failed job's outputs, which Snakemake removes and does not remake while the files made
    from them are present. ``ValueError`` naming those jobs or files and the command that
    redoes them."""
    options = invocation.workflow_options(argv[1:])
    program = _snakemake_program(argv[0])
    pending = dry_run_pending([*program, "--dry-run", *options], "snakemake --report", run)
    if pending:
        jobs = jobs_named(pending)
        total = sum(pending.values())
        raise ValueError(
            "snakemake --report: the results are not up to date with the code, config and "
            f"data that make them; a run would redo {total} job{'s' * (total != 1)}: {jobs}. "
            "A report now would show results that no longer follow from them: run "
            f"`snakemake {shlex.join(options)}` first, then the report"
        )
    missing = run_missing_outputs([*program, "--summary", *options], "snakemake --report", run)
    if missing:
        rules = sorted(set(missing.values()))
        raise ValueError(
            f"snakemake --report: {missing_files_named(missing)}, such as a failed job's "
            "outputs, which Snakemake removed and does not remake while the files made from "
            "them are present: a report now would show what those files held before. Run "
            f"`snakemake {shlex.join(['--forcerun', *rules, *options])}` first, then the report"
        )


def _snakemake_program(first: str) -> list[str]:
    """How to start the Snakemake a command line's first word ``first`` started: its script
    by this interpreter, or ``-m snakemake`` where it was the package's ``__main__``, which
    does not run as a script."""
    if Path(first).name == "__main__.py":
        return [sys.executable, "-m", "snakemake"]
    return [sys.executable, first]


def run_missing_outputs(
    command: Sequence[str],
    what: str,
    run: Callable[..., subprocess.CompletedProcess] = subprocess.run,
) -> dict[str, str]:
    """:func:`missing_outputs` of the ``snakemake --summary`` ``command``, which ``what`` (the
    command asking) runs to learn whether the files of the run are present: a failed job's
    outputs, which Snakemake removes, are not remade, nor listed by a dry run, while the files
    made from them are present. ``ValueError`` with the summary's output where it fails."""
    return missing_outputs(
        _output(command, what, "the summary that checks the results are present", run)
    )


def missing_files_named(missing: dict[str, str]) -> str:
    """How many of the run's files ``missing`` (:func:`missing_outputs`) names and the first
    five of them, as a refusal says it."""
    files = ", ".join(list(missing)[:5]) + (", ..." if len(missing) > 5 else "")
    are = "are" if len(missing) != 1 else "is"
    return f"{len(missing)} file{'s' * (len(missing) != 1)} of the run {are} missing ({files})"


def missing_outputs(summary: str) -> dict[str, str]:
    """``{file: rule}`` of the rows of a ``snakemake --summary`` table (tab-separated: file,
    date, rule, logs, status, plan) whose status is ``missing``."""
    missing = {}
    for line in summary.splitlines():
        fields = line.split("\t")
        if len(fields) >= 5 and fields[4] == "missing":
            missing[fields[0]] = fields[2]
    return missing


def _failed_job_logs(block: str) -> str:
    """The logs Snakemake names in the error ``block`` of a failed job, as it lists them: the
    rule's, and on a cluster the cluster job's own after it (the one that says a job was killed
    for its memory or time); "no log" where it names none."""
    found = re.search(
        r"^ {4}log: (.+?)(?: \(check log file\(s\) for error details\))?$", block, re.M
    )
    return found.group(1) if found else "no log"


def failure_lines(
    logs: Path | str | Sequence[Path | str], environ: Mapping[str, str] = os.environ
) -> str:
    """What a run that failed prints last, read from its Snakemake ``logs`` (a file, or the
    list of them Snakemake's ``onerror`` gives): each failed
    job's rule and log, or the files it did not write when its program exited 0 without them
    (a run that keeps going reports its first error far above its end),
    and the command, with the options of the run recorded in ``environ``, that remakes their
    outputs and everything after them once the cause is mended: Snakemake removed those
    outputs, and a plain run may find nothing to do while files made from them earlier are
    present. Empty where the logs name no failed job (or are not there)."""
    paths = [Path(logs)] if isinstance(logs, str | Path) else [Path(log) for log in logs]
    text = "".join(path.read_text(errors="replace") for path in paths if path.is_file())
    failed = _errors(text) + _missing_outputs(text)
    if not failed:
        return ""
    lines = [f"jointbench: {len(failed)} job{'s' * (len(failed) != 1)} failed:"]
    lines += [f"  {rule}: {where}" for rule, where in failed]
    rules = sorted({rule for rule, _ in failed})
    command = invocation.snakemake_command("--forcerun", *rules, environ=environ)
    lines.append(
        "The other jobs' results are kept. Snakemake removed the failed jobs' outputs: once "
        f"the cause is mended, `{command}` makes them and everything after them again (a "
        "plain run may find nothing to do while the files made from them earlier are present)."
    )
    return "\n".join(lines)


def _errors(text: str) -> list[tuple[str, str]]:
    """Each job of a Snakemake log ``text`` that failed with an ``Error in rule`` block (its
    program exited non-zero, or its script raised), as its rule and its logs
    (:func:`_failed_job_logs`)."""
    return [
        (rule, _failed_job_logs(block))
        for rule, block in re.findall(r"^Error in rule (\S+):\n((?: {4}.*\n?)*)", text, re.M)
    ]


def _missing_outputs(text: str) -> list[tuple[str, str]]:
    """Each job of a Snakemake log ``text`` whose program exited 0 without writing its outputs,
    as its rule and the files it did not write: Snakemake fails such a job with a
    ``MissingOutputException`` block, not the ``Error in rule`` block of a job that exited
    non-zero, yet the job failed all the same."""
    blocks = re.findall(
        r"^MissingOutputException in rule (\S+) in file .*\n.*\n((?:.* \(missing locally.*\n?)*)",
        text,
        re.M,
    )
    return [
        (rule, "wrote no " + ", ".join(re.findall(r"^(.*) \(missing locally", files, re.M)))
        for rule, files in blocks
    ]


def closing_lines(environ: Mapping[str, str] = os.environ) -> str:
    """What a successful run prints last: where the results are and how to make the report,
    with the options of the run (:func:`jointbench.invocation.snakemake_command`, as recorded
    in ``environ``), whose config decides which outputs the report shows."""
    command = invocation.snakemake_command("--report", REPORT_FILE, environ=environ)
    return (
        "Done. Figures in results/figures/, tables in results/tables/ (what each file holds: "
        "results/README.md).\n"
        f"The report: {command}, then open {REPORT_FILE}."
    )
