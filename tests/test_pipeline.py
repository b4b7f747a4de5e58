"""The real Snakemake workflow, end to end, on a reduced config in a temporary directory."""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest
import yaml
from workflow_copy import ROOT, SNAKEMAKE, copy_workflow, load_benchmark, run_snakemake

from jointbench.papers import papers_of_study

pytestmark = pytest.mark.pipeline

compare_collected = load_benchmark("compare_collected")


def _outputs(study: str) -> list[str]:
    """Every file a study's paper outputs and extended ranking write, from the registries."""
    files = [f"collected/{study}.parquet"]
    for paper in papers_of_study(study):
        for output in paper.outputs:
            files += [path.removeprefix("results/") for path in output.files.values()]
    files += [f"tables/extended_{study}.html", f"figures/extended_{study}.png"]
    return files


def test_every_output_is_produced(reduced_run):
    workdir, reduced = reduced_run.workdir, reduced_run.overlay
    for study in reduced["studies"]:
        for name in _outputs(study):
            path = workdir / "results" / name
            assert path.exists(), f"missing output results/{name}"
            assert path.stat().st_size > 200, f"results/{name} is nearly empty"


def test_results_readme_describes_every_folder_a_run_writes(reduced_run):
    """results/README.md, the layout the README points to, names every folder a run writes
    under results/, and in its row of poses every study that has them."""
    layout = (ROOT / "results" / "README.md").read_text()
    results = reduced_run.workdir / "results"
    folders = sorted(path.name for path in results.iterdir() if path.is_dir())
    missing = [folder for folder in folders if f"| `{folder}/" not in layout]
    assert not missing, f"results/README.md does not describe {missing}"
    poses = next(line for line in layout.splitlines() if line.startswith("| `poses/"))
    unnamed = [p.name for p in sorted((results / "poses").iterdir()) if f"`{p.name}`" not in poses]
    assert not unnamed, f"results/README.md's poses row does not name {unnamed}"


def test_second_run_has_nothing_to_do(reduced_run):
    second = reduced_run.dry_run
    assert second.returncode == 0
    assert "Nothing to be done" in second.stdout + second.stderr


def test_collected_cmc_has_one_row_per_trial_and_method(reduced_run):
    workdir, reduced = reduced_run.workdir, reduced_run.overlay
    collected = pd.read_parquet(workdir / "results" / "collected" / "cmc.parquet")
    study = reduced["studies"]["cmc"]
    n_conditions = 1
    for values in study["grid"].values():
        n_conditions *= len(values)
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    methods = config["studies"]["cmc"]["estimators"] + config["studies"]["cmc"].get(
        "external_estimators", []
    )
    assert len(collected) == n_conditions * study["trials"] * len(methods)
    required = [
        "marker_set",
        "rom_deg",
        "noise_mm",
        "trial",
        "method",
        "center_x",
        "center_y",
        "center_z",
        "error_mm",
        "converged",
        "iterations",
        "seconds",
        "status",
    ]
    assert set(required) <= set(collected.columns)
    assert set(collected["method"]) == set(methods)


def test_claims_tables_are_computed(reduced_run):
    claims = pd.read_csv(reduced_run.workdir / "results" / "tables" / "paper_a_claims.csv")
    assert list(claims["id"]) == [f"A{i}" for i in range(1, 14)]
    assert set(claims["status"]) <= {"reproduced", "not reproduced", "not applicable"}


def test_the_comparison_says_what_each_status_rests_on(reduced_run):
    """A status in the default run's comparison is one seed's: the table says so, with the
    trials per condition of each study it compares, and where the verdicts over seeds are."""
    tables = reduced_run.workdir / "results" / "tables"
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    trials = {name: study["trials"] for name, study in reduced_run.overlay["studies"].items()}
    for name in ("published_comparison.md", "published_comparison.html"):
        text = (tables / name).read_text()
        assert f"one base seed ({config['base_seed']})" in text, text[-1500:]
        for study in ("cmc", "hinge", "hip", "hip_sta"):
            assert f"{study} {trials[study]}" in text, text[-1500:]
        seeds = config["verdicts"]["seeds"]
        assert f"over {seeds} base seeds: results/tables/verdicts.md" in text, text[-1500:]


def test_every_study_is_reduced():
    reduced = yaml.safe_load((ROOT / "tests" / "data" / "reduced.yaml").read_text())
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    assert set(reduced["studies"]) == set(config["studies"])
    for name, study in reduced["studies"].items():
        assert study["trials"] < config["studies"][name]["trials"]


def test_the_report_holds_every_figure_and_table(reduced_run, tmp_path):
    # Written outside the run, which stays as finished: a copy elsewhere would be out of date
    # (Snakemake records the published values' files by absolute path), and refused a report.
    reduced = reduced_run.overlay
    report = reduced_run.snakemake("--report", str(tmp_path / "report.html"))
    assert report.returncode == 0, report.stderr[-4000:]
    html = (tmp_path / "report.html").read_text(errors="replace")
    # Each output is shown on a page of its own beside its caption.
    pages = set(re.findall(r"results/report/pages/(\w+)\.html", html))
    for study in reduced["studies"]:
        for name in _outputs(study):
            if name.endswith((".png", ".html")) and not name.startswith("collected"):
                stem = name.split("/")[-1].rsplit(".", 1)[0]
                page = f"{stem}_figure" if name.endswith(".png") and "extended_" in stem else stem
                assert page in pages, f"{name} missing from the report"
    assert "published_comparison" in pages
    assert "Findings" in html, "the report does not open on its findings"
    assert "<title>jointbench" in html, "the report keeps Snakemake's tab title"


def test_a_report_of_results_an_edit_made_stale_is_refused(reduced_run, tmp_path):
    """An edit the results have not been remade after (here the figures' script): the report
    would show what the old code made, so it stops, naming the jobs a run would rerun and the
    command that reruns them."""
    script = reduced_run.workdir / "workflow" / "scripts" / "render.py"
    original, stat = script.read_text(), script.stat()
    script.write_text(original + '\nlog_note = "rendered"\n')
    try:
        report = reduced_run.snakemake("--report", str(tmp_path / "report.html"))
    finally:
        script.write_text(original)
        os.utime(script, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    message = report.stdout + report.stderr
    assert report.returncode != 0
    assert not (tmp_path / "report.html").exists()
    assert "not up to date" in message and "render_cmc" in message, message[-3000:]
    assert f"--configfile {reduced_run.workdir / 'overlay.yaml'}" in message, message[-3000:]


def _jointbench(run, *argv: str) -> subprocess.CompletedProcess:
    """``jointbench *argv`` in ``run``'s folder, on its copy of the package."""
    code = "import sys; from jointbench.cli import main; sys.exit(main(sys.argv[1:]))"
    environment = {**os.environ, "PYTHONPATH": str(run.workdir / "src")}
    return subprocess.run(
        [sys.executable, "-c", code, *argv],
        cwd=run.workdir,
        capture_output=True,
        text=True,
        env=environment,
    )


def test_a_snapshot_or_readme_of_results_an_edit_made_stale_is_refused(reduced_run, tmp_path):
    """`jointbench snapshot` and `jointbench readme` read the run's results: while they are up
    to date both write; after an edit they have not been remade after (the figures' script),
    both stop before writing anything, naming the jobs `snakemake -j2` would redo."""
    readme = tmp_path / "README.md"
    readme.write_text("<!-- reproduction-summary:start -->\n<!-- reproduction-summary:end -->\n")
    snapshot = ("snapshot", "--configfile", "overlay.yaml", "--output", str(tmp_path / "a.csv"))
    rewrite = ("readme", "--configfile", "overlay.yaml", "--readme", str(readme))
    current = [_jointbench(reduced_run, *snapshot), _jointbench(reduced_run, *rewrite)]
    assert [done.returncode for done in current] == [0, 0], [d.stderr for d in current]
    assert (tmp_path / "a.csv").is_file() and _summary_block(readme)
    readme.write_text("<!-- reproduction-summary:start -->\n<!-- reproduction-summary:end -->\n")
    script = reduced_run.workdir / "workflow" / "scripts" / "render.py"
    original, stat = script.read_text(), script.stat()
    script.write_text(original + '\nlog_note = "rendered"\n')
    try:
        stale = [
            _jointbench(reduced_run, *snapshot[:-1], str(tmp_path / "b.csv")),
            _jointbench(reduced_run, *rewrite),
        ]
    finally:
        script.write_text(original)
        os.utime(script, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    for done in stale:
        assert done.returncode == 1, done.stderr
        assert "is not up to date" in done.stderr and "render_cmc (1)" in done.stderr
        assert "`snakemake -j2 --configfile overlay.yaml` would redo" in done.stderr
    assert not (tmp_path / "b.csv").exists()
    assert not _summary_block(readme)


def _summary_block(readme) -> str:
    """What the README's reproduction-summary block holds."""
    return readme.read_text().partition("summary:start -->")[2].partition("<!--")[0].strip()


def test_every_rule_writes_its_log(reduced_run):
    workdir = reduced_run.workdir
    logs = list((workdir / "results" / "logs").rglob("*.log"))
    assert logs, "no logs written"
    empty = [str(p.relative_to(workdir)) for p in logs if p.stat().st_size == 0]
    assert not empty, f"empty logs: {empty}"


def test_estimate_jobs_log_their_progress(reduced_run):
    log = (reduced_run.workdir / "results" / "logs" / "estimate" / "cmc" / "NM.log").read_text()
    assert "cmc NM: [" in log and "conditions" in log and "s left" in log


def test_the_hip_methods_share_one_pose_fit_per_condition(reduced_run):
    """One poses job fits the hip trials; each pose-based estimate job reads its files."""
    workdir, reduced = reduced_run.workdir, reduced_run.overlay
    conditions = reduced["studies"]["hip"]["grid"]["n_frames"]
    poses = sorted(p.name for p in (workdir / "results" / "poses" / "hip").glob("*.parquet"))
    assert poses == sorted(f"n_frames-{n}.parquet" for n in conditions)
    log = (workdir / "results" / "logs" / "poses" / "hip.log").read_text()
    assert f"hip poses: [####################] {len(conditions)}/{len(conditions)}" in log
    jobs = reduced_run.snakemake("--dry-run", "--forceall")
    assert jobs.returncode == 0, jobs.stderr[-2000:]
    stats = jobs.stdout + jobs.stderr
    assert re.search(r"^poses_hip\s+1$", stats, re.MULTILINE), stats
    assert "poses_cmc" not in stats and "poses_hinge" not in stats
    # One job per condition for a cluster: a poses job per condition, read by that condition's
    # estimate jobs.
    per_condition = reduced_run.snakemake(
        "--dry-run", "--forceall", "--config", "jobs={'estimate': 'per_condition'}"
    )
    assert per_condition.returncode == 0, per_condition.stderr[-2000:]
    stats = per_condition.stdout + per_condition.stderr
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    n_methods = len(config["studies"]["hip"]["estimators"])
    assert re.search(rf"^poses_hip\s+{len(conditions)}$", stats, re.MULTILINE), stats
    assert re.search(rf"^estimate_hip\s+{n_methods * len(conditions)}$", stats, re.MULTILINE)


def test_a_grid_without_a_figures_condition_runs_without_that_figure(tmp_path):
    """A custom grid lacking M / 5° / 1.0 mm skips Fig 3 with a one-line note, not a crash."""
    workdir = copy_workflow(tmp_path)
    overlay = tmp_path / "grid.yaml"
    overlay.write_text(
        "studies:\n  cmc:\n    trials: 2\n    grid: {marker_set: [H], rom_deg: [15], "
        "noise_mm: [0.5]}\n  hinge: {enabled: false}\n  hip: {enabled: false}\n"
    )
    run = run_snakemake(workdir, "--configfile", str(overlay), "--dry-run")
    assert run.returncode == 0, run.stderr[-3000:]
    assert "note: paper_a_fig3 skipped" in run.stderr
    # Paper A's job still renders its other outputs; no rule makes Fig 3.
    for figure, made in (("paper_a_fig4", True), ("paper_a_fig3", False)):
        target = f"results/figures/{figure}.png"
        run = run_snakemake(workdir, "--configfile", str(overlay), "--dry-run", target)
        assert (run.returncode == 0) is made, run.stderr[-3000:]


def test_the_per_condition_grain_gives_the_default_grains_results(tmp_path):
    """The cluster grain (one estimate job per condition) runs every study, the external LM rule
    included, and collects the same values as the default grain, timings aside."""
    grains = ROOT / "tests" / "data" / "grains.yaml"
    per_condition = ROOT / "config" / "variants" / "per_condition.yaml"
    targets = [f"results/collected/{study}.parquet" for study in ("cmc", "hinge", "hip")]
    runs = {}
    for name, overlays in (("default", [grains]), ("per_condition", [grains, per_condition])):
        (tmp_path / name).mkdir()
        workdir = copy_workflow(tmp_path / name)
        run = run_snakemake(workdir, *targets, "--configfile", *map(str, overlays))
        assert run.returncode == 0, f"{name}: {run.stderr[-4000:]}"
        runs[name] = workdir
    # The overlay took effect: one log per condition of an estimator, not one per estimator.
    per_job_logs = runs["per_condition"] / "results" / "logs" / "estimate" / "hip" / "analytic"
    assert sorted(p.name for p in per_job_logs.glob("*.log")) == [
        "n_frames-16.log",
        "n_frames-75.log",
    ]
    differences = compare_collected.compare_runs(runs["default"], runs["per_condition"])
    assert set(differences) == {"cmc", "hinge", "hip"}
    assert not any(differences.values()), differences
    methods = set(pd.read_parquet(runs["per_condition"] / targets[0])["method"])
    assert methods == {"NM", "LS", "LM"}


def _readme_commands(heading: str) -> list[str]:
    """The commands of the first shell block after the README line holding ``heading``."""
    readme = (ROOT / "README.md").read_text()
    after = readme[readme.index(heading) :]
    block = re.search(r"```bash\n(.*?)```", after, re.DOTALL)[1]
    return [line.strip() for line in block.splitlines() if line.strip()]


def test_the_readmes_recovery_steps_finish_a_run_killed_mid_job(tmp_path):
    """`kill -9` of a running Snakemake (and its jobs) leaves a lock and incomplete files; the
    README's commands, run as written, finish the run."""
    workdir = copy_workflow(tmp_path)
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    config["studies"]["cmc"].update(
        trials=2,
        grid={"marker_set": ["M"], "rom_deg": [5], "noise_mm": [1.0]},
        estimators=["NM", "LS"],
        external_estimators=[],
    )
    # One small study is enough to kill a run mid-job; the others, and an external estimator's
    # jobs, would only lengthen it.
    for study in config["studies"].keys() - {"cmc"}:
        config["studies"][study]["enabled"] = False
    # The user's own config, so that the README's commands need no --configfile.
    (workdir / "config" / "config.yaml").write_text(yaml.safe_dump(config))
    environment = {**os.environ, "PATH": f"{SNAKEMAKE.parent}{os.pathsep}{os.environ['PATH']}"}

    def shell(command: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            shlex.split(command),
            cwd=workdir,
            env=environment,
            capture_output=True,
            text=True,
            timeout=300,
        )

    running = subprocess.Popen(
        ["snakemake", "-j2"],
        cwd=workdir,
        env=environment,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    incomplete = workdir / ".snakemake" / "incomplete"
    deadline = time.monotonic() + 120
    while not (incomplete.is_dir() and any(incomplete.iterdir())):
        assert running.poll() is None, "the run ended before a job was seen running"
        assert time.monotonic() < deadline, "no job started within 120 s"
        time.sleep(0.05)
    os.killpg(running.pid, signal.SIGKILL)  # its session: Snakemake and the job it runs
    running.wait()

    locked = shell("snakemake -j2 --rerun-incomplete")
    assert locked.returncode != 0 and "LockException" in locked.stdout + locked.stderr
    commands = _readme_commands("**A run was interrupted**")
    assert commands == ["snakemake --unlock", "snakemake -j2 --rerun-incomplete"]
    for command in commands:
        done = shell(command)
        assert done.returncode == 0, f"{command}: {done.stderr[-3000:]}"
    finished = shell("snakemake -j2 --dry-run")
    assert "Nothing to be done" in finished.stdout + finished.stderr
