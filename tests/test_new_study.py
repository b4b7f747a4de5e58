"""The recipe of docs/architecture.md: a study in the package is three new files (a simulator
module, a paper module and its published values) and one edit (its config block); nothing
else is registered by hand. Tried on a copy of the package with a toy study, run through the
library in a fresh interpreter that imports the copy."""

from __future__ import annotations

import filecmp
import os
import shutil
import subprocess
import sys
import textwrap

from workflow_copy import ROOT

DATA = ROOT / "tests" / "data" / "new_study"
NEW_FILES = {"simulate/toy.py": "toy.py", "papers/paper_t.py": "paper_t.py"}
NEW_FILES["papers/paper_t.yaml"] = "paper_t.yaml"


def _changed(original, copy) -> tuple[set[str], set[str]]:
    """Files only in ``copy`` and files in both that differ, relative to ``copy``."""
    added, edited = set(), set()
    for path in copy.rglob("*"):
        if path.is_dir() or "__pycache__" in path.parts:
            continue
        relative = path.relative_to(copy)
        twin = original / relative
        if not twin.exists():
            added.add(str(relative))
        elif not filecmp.cmp(path, twin, shallow=False):
            edited.add(str(relative))
    return added, edited


def test_a_study_in_the_package_takes_three_files_and_one_edit(tmp_path):
    package = tmp_path / "src" / "jointbench"
    # With its caches (which _changed leaves out): the copy's kernels are not compiled again.
    shutil.copytree(ROOT / "src" / "jointbench", package)
    shutil.copytree(ROOT / "config", tmp_path / "config")
    for target, source in NEW_FILES.items():
        shutil.copy(DATA / source, package / target)
    config = tmp_path / "config" / "config.yaml"
    text = config.read_text()
    config.write_text(
        text.replace("studies:\n", "studies:\n" + (DATA / "config_block.yaml").read_text(), 1)
    )

    (added, edited), (added_config, edited_config) = (
        _changed(ROOT / folder, tmp_path / folder) for folder in ("src", "config")
    )
    added, edited = added | added_config, edited | edited_config
    assert len(added) == 3 and len(edited) <= 2, (added, edited)

    code = textwrap.dedent(
        """
        import sys

        import pandas as pd
        import jointbench
        from jointbench.figures import extended
        from jointbench.papers import Inputs, get_paper
        from jointbench.comparison import published
        from jointbench.running import run
        from jointbench.configuration.config import conditions, load_config

        assert jointbench.__file__.startswith(sys.argv[1]), jointbench.__file__
        config = load_config("config/config.yaml")
        rows = []
        for condition in conditions(config, "toy"):
            trials = run.simulate_condition(config, "toy", condition)
            for method in ("NM", "LS"):
                rows.append(run.estimate(method=method, study="toy", trials=trials,
                                         condition=condition))
        collected = pd.concat(rows, ignore_index=True)
        paper = get_paper("paper_t")
        document = published.load_published(paper.published)
        inputs = Inputs(collected=collected, published=document, config=config)
        comparison = published.comparison_rows(document, paper.measure(inputs))
        print(comparison.set_index("id").loc["T1", "status"])
        print(paper.output("paper_t_errors").render(inputs).frame.shape)
        print(extended.condition_label("toy", (0.5,)))
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(package)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(tmp_path / "src")},
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.splitlines() == ["reproduced", "(2, 3)", "σ 0.5 mm"]
