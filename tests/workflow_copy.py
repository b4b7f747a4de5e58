"""Helpers for the end-to-end tests: the workflow as a user clones it, and running Snakemake."""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
OVERLAY = "overlay.yaml"


def load_benchmark(name: str):
    """A script of benchmarks/ as a module (benchmarks/ is not a package)."""
    spec = importlib.util.spec_from_file_location(
        f"benchmarks_{name}", ROOT / "benchmarks" / f"{name}.py"
    )
    module = importlib.util.module_from_spec(spec)
    # Registered first: dataclasses look their module up while the class is being made.
    sys.modules[f"benchmarks_{name}"] = module
    spec.loader.exec_module(module)
    return module


def readme_builtin_example() -> tuple[str, dict]:
    """The README's "Built in: one function": its estimator's code, as a user copies it into
    the package, and the config that lists it."""
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("### Built in: one function") : readme.index("### Any language")]
    code = re.search(r"```python\n(.*?)```", section, re.DOTALL).group(1)
    listing = re.search(r"```yaml\n(.*?)```", section, re.DOTALL).group(1)
    return code, yaml.safe_load(listing)


def copy_workflow(destination: Path, *, profiles: bool = False) -> Path:
    """Copy the files a user clones (Snakefile, workflow/, config/, and with ``profiles``
    profiles/) into the folder ``destination``; results/ starts empty. Snakemake applies
    profiles/default wherever the copy holds it; the end-to-end tests run without it, which
    would hide each job's rule and wildcards."""
    shutil.copy(ROOT / "Snakefile", destination / "Snakefile")
    for folder in ("workflow", "config", *(["profiles"] if profiles else [])):
        shutil.copytree(ROOT / folder, destination / folder)
    return destination


def running_in(folder: Path) -> list[int]:
    """The pids of the processes whose working directory is ``folder`` or below it: what is
    left of a run's jobs, which Snakemake starts in its ``--directory``, however far each got
    (a program stopped before it could write its pid is found too). A zombie, which runs
    nothing, has no working directory to read."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            where = Path(os.readlink(entry / "cwd"))
        except OSError:  # not a process, one that ended, or another user's
            continue
        if where == folder.resolve() or folder.resolve() in where.parents:
            found.append(int(entry.name))
    return found


def run_snakemake(workdir: Path, *arguments: str, timeout: int = 900, jobs: int = 2):
    """Run ``snakemake -j2`` (``jobs`` at a time) on the copy in ``workdir`` with extra
    arguments (targets first)."""
    command = [
        str(SNAKEMAKE),
        *arguments,
        f"-j{jobs}",
        "--directory",
        str(workdir),
        "-s",
        str(workdir / "Snakefile"),
    ]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout)


def refused_dry_run(workdir: Path, overlay: dict) -> str:
    """Copy the workflow into ``workdir`` and dry-run it with the config file ``overlay``,
    which it must refuse before planning any job or writing any result; its messages."""
    copy_workflow(workdir)
    path = workdir / "overlay.yaml"
    path.write_text(yaml.safe_dump(overlay))
    run = run_snakemake(workdir, "--configfile", str(path), "--dry-run", timeout=300)
    message = run.stdout + run.stderr
    assert run.returncode != 0, message[-2000:]
    assert "Job stats" not in message, message[-2000:]
    assert not (workdir / "results").exists()
    return message


@dataclass(frozen=True)
class FinishedRun:
    """A finished run in ``workdir``: the workflow, its own copy of the package under ``src/``
    and its config overlay ``overlay.yaml`` (``overlay``, as loaded); ``dry_run``, the dry run
    made once it had finished."""

    workdir: Path
    overlay: dict
    dry_run: subprocess.CompletedProcess | None = None

    def snakemake(self, *arguments: str, timeout: int = 900) -> subprocess.CompletedProcess:
        """``snakemake -j2`` with ``arguments`` (targets first) on this run's tree, config
        overlay and copy of the package."""
        command = [
            str(SNAKEMAKE),
            *arguments,
            "-j2",
            # A repository's default profile would hide each job's rule and wildcards.
            "--workflow-profile",
            "none",
            "--directory",
            str(self.workdir),
            "-s",
            str(self.workdir / "Snakefile"),
            "--configfile",
            str(self.workdir / OVERLAY),
        ]
        environment = {**os.environ, "PYTHONPATH": str(self.workdir / "src")}
        return subprocess.run(
            command, capture_output=True, text=True, timeout=timeout, env=environment
        )

    def finished(self) -> FinishedRun:
        """This run with its dry run, which must have nothing to do."""
        again = self.snakemake("--dry-run")
        assert again.returncode == 0, again.stderr[-4000:]
        assert "Nothing to be done" in again.stdout, again.stdout[-4000:]
        return FinishedRun(self.workdir, self.overlay, again)

    def copy(self, destination: Path) -> FinishedRun:
        """This run copied into the new directory ``destination``, to write into (a report).
        Its files keep their times, but Snakemake records the published-value files a job
        reads by absolute path, so there the jobs reading them count as changed: ask the
        original, not a copy, what is out of date."""
        shutil.copytree(self.workdir, destination, symlinks=True)
        return FinishedRun(destination, self.overlay)


def finish_run(
    workdir: Path,
    overlay: dict,
    extension_files: tuple[Path, ...] = (),
    library_files: tuple[Path, ...] = (),
) -> FinishedRun:
    """Run ``overlay`` to the end in ``workdir``, with a copy of the package and the files of
    an extension, and ``library_files`` (modules of the user's own that an extension imports)
    beside the package, on the jobs' ``PYTHONPATH``; the run must then have nothing left to
    do."""
    shutil.copy(ROOT / "Snakefile", workdir / "Snakefile")
    for folder in ("workflow", "config"):
        shutil.copytree(ROOT / folder, workdir / folder)
    # Compiled kernels' caches come along (their sources keep their times): no job recompiles.
    shutil.copytree(ROOT / "src", workdir / "src", ignore=shutil.ignore_patterns("*.egg-info"))
    for path in extension_files:
        shutil.copy2(path, workdir / path.name)
    for path in library_files:
        shutil.copy2(path, workdir / "src" / path.name)
    (workdir / OVERLAY).write_text(yaml.safe_dump(overlay))
    run = FinishedRun(workdir, overlay)
    done = run.snakemake()
    assert done.returncode == 0, done.stderr[-4000:]
    return run.finished()
