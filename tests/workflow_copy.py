"""Helpers for the end-to-end tests: the workflow as a user clones it, and running Snakemake."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")


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


def copy_workflow(destination: Path) -> Path:
    """Copy the files a user clones (Snakefile, workflow/, config/); results/ starts empty."""
    shutil.copy(ROOT / "Snakefile", destination / "Snakefile")
    shutil.copytree(ROOT / "workflow", destination / "workflow")
    shutil.copytree(ROOT / "config", destination / "config")
    return destination


def run_snakemake(workdir: Path, *arguments: str, timeout: int = 900):
    """Run ``snakemake -j2`` on the copy in ``workdir`` with extra arguments (targets first)."""
    command = [
        str(SNAKEMAKE),
        *arguments,
        "-j2",
        "--directory",
        str(workdir),
        "-s",
        str(workdir / "Snakefile"),
    ]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout)
