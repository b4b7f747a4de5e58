"""The report's texts and finishing, and the workflow's console, on small inputs."""

from __future__ import annotations

import logging
import subprocess

import pandas as pd
import pytest

from jointbench import console, invocation, report
from jointbench.figures.paper_c import calibration_status
from jointbench.papers import paper_c


@pytest.mark.parametrize(
    ("argv", "path"),
    [
        (["snakemake", "--report", "results/report.html"], "results/report.html"),
        (["snakemake", "--report=out.html"], "out.html"),
        (["snakemake", "--report", "-j2"], "report.html"),
        (["snakemake", "-j2"], None),
        (["snakemake", "--report", "r.html", "--directory", "/tmp/w"], "/tmp/w/r.html"),
    ],
)
def test_the_report_path_is_read_from_the_command_line(argv, path):
    assert report.report_path(argv) == path


# What `snakemake --dry-run` prints when it has jobs to do: the job stats, once before the jobs
# and once after them.
JOB_STATS = """Job stats:
job                count
---------------  -------
render_cmc             1
check_published        1
all                    1
total                  3
"""
DRY_RUN = (
    f"Building DAG of jobs...\n{JOB_STATS}\nrule render_cmc:\n"
    f"    input: results/collected/cmc.parquet\n{JOB_STATS}"
    "This was a dry-run (flag -n). The order of jobs does not reflect the order of execution.\n"
)
UP_TO_DATE = "Building DAG of jobs...\nNothing to be done (all requested files are present).\n"


def test_a_dry_runs_jobs_are_read_by_rule():
    assert report.pending_jobs(DRY_RUN) == {"render_cmc": 1, "check_published": 1}
    assert report.pending_jobs(UP_TO_DATE) == {}


def test_pending_jobs_are_named_by_rule_and_count():
    """One way of naming a dry run's jobs, for every command that refuses stale results."""
    assert report.jobs_named(report.pending_jobs(DRY_RUN)) == "render_cmc (1), check_published (1)"


def _dry_run(stdout: str, returncode: int = 0, stderr: str = ""):
    """A stand-in for ``subprocess.run`` answering as a dry run would, and the commands it
    was given."""
    commands = []

    def run(command, **_):
        commands.append(command)
        return subprocess.CompletedProcess(command, returncode, stdout, stderr)

    return run, commands


ARGV = ["/venv/bin/snakemake", "--report", "r.html", "--configfile", "my.yaml", "-j2"]


def test_a_report_of_up_to_date_results_goes_ahead():
    run, commands = _dry_run(UP_TO_DATE)
    assert report.check_current(ARGV, run) is None
    # The same program on the same config and workflow, without the report: a dry run, then
    # the summary that says whether a file of the run is missing.
    dry, summary = commands
    options = ["--configfile", "my.yaml", "--jobs", "2"]
    assert dry[1:] == ["/venv/bin/snakemake", "--dry-run", *options]
    assert summary[1:] == ["/venv/bin/snakemake", "--summary", *options]


# What `snakemake --summary` prints after a failed job, whose outputs Snakemake removed: the
# run's own plan has nothing to redo while the collected file made from them is present.
SUMMARY = (
    "output_file\tdate\trule\tlog-file(s)\tstatus\tplan\n"
    "results/collected/cmc.parquet\tSat Dec  5 07:44:32 2026\tcollect\tlog\tok\tno update\n"
    "results/estimates/cmc/LM/a.parquet\t-\testimate_cmc_LM\tlog\tmissing\tno update\n"
)


def test_a_report_with_files_a_failed_job_left_missing_is_refused_naming_them():
    """After a job failed, Snakemake's next run has nothing to do while the files made from its
    removed outputs are present; the report is refused, naming the files and the command that
    makes them again."""
    answers = iter([UP_TO_DATE, SUMMARY])

    def run(command, **_):
        return subprocess.CompletedProcess(command, 0, next(answers), "")

    with pytest.raises(ValueError) as refused:
        report.check_current(ARGV, run)
    message = str(refused.value)
    assert "1 file of the run is missing (results/estimates/cmc/LM/a.parquet)" in message
    assert "`snakemake --forcerun estimate_cmc_LM --configfile my.yaml --jobs 2` first" in message


def test_a_report_asked_of_python_m_snakemake_asks_it_the_same_way():
    """``python -m snakemake --report`` has the package's ``__main__`` as its first word, which
    does not run as a script: the checks start ``-m snakemake`` too."""
    run, commands = _dry_run(UP_TO_DATE)
    report.check_current(["/venv/lib/snakemake/__main__.py", "--report"], run)
    assert all(command[1:3] == ["-m", "snakemake"] for command in commands)


def test_a_report_of_results_a_run_would_redo_is_refused_naming_the_jobs_and_the_command():
    run, _ = _dry_run(DRY_RUN)
    with pytest.raises(ValueError) as refused:
        report.check_current(ARGV, run)
    message = str(refused.value)
    assert "not up to date" in message
    assert "would redo 2 jobs: render_cmc (1), check_published (1)" in message
    assert "`snakemake --configfile my.yaml --jobs 2` first" in message


def test_a_dry_run_that_fails_stops_the_report_with_its_error():
    run, _ = _dry_run("", returncode=1, stderr="config: studies.cmc.trials: must be ...")
    with pytest.raises(ValueError, match=r"config: studies\.cmc\.trials"):
        report.check_current(ARGV, run)


@pytest.mark.parametrize(
    ("argv", "command"),
    [
        (None, "snakemake -j2 --report results/report.html"),
        (["-j2"], "snakemake --jobs 2 --report results/report.html"),
        (
            ["study_cmc", "-j2", "--configfile", "my.yaml", "more.yaml"],
            "snakemake --configfile my.yaml more.yaml --jobs 2 --report results/report.html",
        ),
    ],
)
def test_a_run_closes_with_the_report_command_of_its_own_config(argv, command):
    """The report of a run over an overlay is made with that overlay: without it Snakemake
    looks for the default config's outputs, which that run did not make."""
    environ = {}
    if argv is not None:
        invocation.record(argv, environ)
    assert f"The report: {command}, then open" in report.closing_lines(environ)


def test_finishing_titles_the_report_and_starts_it_at_the_top(tmp_path):
    page = tmp_path / "report.html"
    page.write_text("<html><head><title>Snakemake Report</title></head><body></body></html>")
    assert report.finish_report(page)
    assert report.finish_report(page)  # twice is once
    text = page.read_text()
    assert f"<title>{report.REPORT_TITLE}</title>" in text
    assert text.count("jointbench-style") == 1 and "align-items: flex-start" in text
    assert not report.finish_report(tmp_path / "missing.html")


@pytest.mark.parametrize(
    ("name", "label"),
    [
        ("paper_a_fig3", "Fig 3"),
        ("paper_b_table1", "Table 1"),
        ("paper_c_claims", "Claims"),
        ("extended_cmc_figure", "Extended ranking (figure)"),
        ("published_comparison", "Every value and claim"),
    ],
)
def test_outputs_are_listed_by_names_for_people(name, label):
    assert report.output_label(name) == label


def test_a_calibration_on_the_band_edge_is_borderline_and_said_so():
    assert calibration_status(0.98, 0.92, 0.98) == "borderline"
    assert calibration_status(0.95, 0.92, 0.98) == "calibrated"
    assert calibration_status(0.5, 0.92, 0.98) == "overconfident"
    assert calibration_status(0.99, 0.92, 0.98) == "conservative"
    table = pd.DataFrame(
        {
            "method": ["f0"] * 3,
            "n_frames": [4, 8, 16],
            "inside_95": [0.98, 0.955, 0.945],
            "status": ["borderline", "calibrated", "calibrated"],
        }
    )
    sentence = paper_c.calibration_sentence(table)
    assert "calibrated at every Nt from 8 on" in sentence and "borderline at Nt = 4" in sentence


def test_an_output_page_shows_the_figure_beside_its_caption(tmp_path):
    png = tmp_path / "fig.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n")
    page = report.output_page("Paper A Fig 3", "What it shows, **in bold**.", png)
    assert "data:image/png;base64," in page and "<strong>in bold</strong>" in page
    assert "class='caption'" in page and "Paper A Fig 3" in page


def _record(msg, **extra):
    record = logging.LogRecord("snakemake", logging.INFO, "", 0, msg, None, None)
    record.__dict__.update(extra)
    return record


def test_the_console_shows_one_line_per_job_and_drops_the_chatter():
    assert not console.shown(_record("Select jobs to execute..."))
    assert not console.shown(_record("Execute 1 jobs..."))
    assert console.shown(_record("12 of 28 steps (43%) done"))
    job = _record(None, event="job_info", rule_msg="estimate cmc: NM on 18 conditions")
    assert console.shown(job)
    assert console.job_line(job) == "estimate cmc: NM on 18 conditions"
    target = _record(None, event="job_info", rule_msg=None, rule_name="all", output=[])
    assert not console.shown(target)


# The block a Snakemake log holds for a failed job, as a run's log file keeps it.
FAILED_LOG = (
    "[Sat Dec  5 08:24:10 2026]\n"
    "Error in rule estimate_centroid:\n"
    "    message: None\n"
    "    jobid: 2\n"
    "    input: results/blind/cmc/a.parquet\n"
    "    output: results/estimates/cmc/centroid/a.parquet\n"
    "    log: results/logs/estimate/cmc/centroid/a.log (check log file(s) for error details)\n"
    "Execute 1 jobs...\n"
)


def test_a_failed_run_ends_naming_each_failed_job_and_the_command_that_redoes_it(tmp_path):
    """A run with keep-going ends long after its first error: its last lines name each failed
    job's rule and log, and the forcerun that remakes their removed outputs once mended."""
    log = tmp_path / "run.log"
    log.write_text(FAILED_LOG * 2)
    environ = {invocation.ENVIRONMENT_VARIABLE: "-j2 --configfile my.yaml"}
    lines = report.failure_lines([log], environ)
    assert "2 jobs failed" in lines
    assert "estimate_centroid: results/logs/estimate/cmc/centroid/a.log" in lines
    assert "`snakemake -j2 --configfile my.yaml --forcerun estimate_centroid`" in lines
    log.write_text("Execute 1 jobs...\n")
    assert report.failure_lines(log, environ) == ""
    assert report.failure_lines(tmp_path / "absent.log", environ) == ""


# The block a Snakemake log holds for a job whose program exited 0 without writing its output
# (an external estimator that printed its answer to stderr, or nothing): no "Error in rule".
MISSING_OUTPUT_LOG = (
    'MissingOutputException in rule estimate_quiet in file "/w/workflow/rules/estimators/'
    'quiet.smk", line 1:\n'
    "Job 11  completed successfully, but some output files are missing. Missing files after 5 "
    "seconds. This might be due to filesystem latency. If that is the case, consider to "
    "increase the wait time with --latency-wait:\n"
    "results/estimates/cmc/quiet/a.csv (missing locally, parent dir contents: )\n"
    "Select jobs to execute...\n"
)


def test_a_job_that_wrote_no_output_is_counted_and_named_among_the_failed(tmp_path):
    """A program that exits 0 without its output fails its job as surely as one that exits
    non-zero: the last lines count it, name its rule and the file it did not write, and the
    forcerun names its rule too."""
    log = tmp_path / "run.log"
    log.write_text(FAILED_LOG + MISSING_OUTPUT_LOG)
    environ = {invocation.ENVIRONMENT_VARIABLE: "-j2"}
    lines = report.failure_lines([log], environ)
    assert "2 jobs failed" in lines, lines
    assert "estimate_centroid: results/logs/estimate/cmc/centroid/a.log" in lines
    assert "estimate_quiet: wrote no results/estimates/cmc/quiet/a.csv" in lines, lines
    assert "--forcerun estimate_centroid estimate_quiet`" in lines, lines
    log.write_text(MISSING_OUTPUT_LOG)
    assert "1 job failed:\n  estimate_quiet: wrote no " in report.failure_lines(log, environ)


def test_a_failed_cluster_job_is_named_with_its_rules_log_and_the_cluster_jobs_own(tmp_path):
    """Through the SLURM executor a failed job has two logs, the rule's and the cluster job's
    (where a job killed for its memory or time says so): both are named, as Snakemake lists them."""
    slurm_log = "/w/.snakemake/slurm_logs/rule_estimate_cmc_LM/25.log"
    log = tmp_path / "run.log"
    log.write_text(
        FAILED_LOG.replace("estimate_centroid", "estimate_cmc_LM").replace(
            "centroid/a.log (", f"LM.log, {slurm_log} ("
        )
    )
    lines = report.failure_lines(log, {}).splitlines()
    assert f"  estimate_cmc_LM: results/logs/estimate/cmc/LM.log, {slurm_log}" in lines
