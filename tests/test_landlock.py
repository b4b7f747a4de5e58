"""What a job of an external estimator may open under results/ (jointbench.running.landlock): a
process confined to a tree reads and writes what it is granted there, and nothing else there
by any path, nor do the processes it starts; outside the tree it keeps every right.

The end-to-end cases, a program of a run's external estimator, are in tests/test_blind.py.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from jointbench.running import landlock, timelimit

pytestmark = pytest.mark.skipif(landlock.abi_version() == 0, reason="this kernel has no Landlock")

# A tree confined to outside /tmp, where every test's own files are: a folder leading to the
# hidden one may not be written in, and /tmp must stay writable, as it is in a real checkout.
TREES = "/var/tmp"


@pytest.fixture
def tree() -> Iterator[Path]:
    """A checkout's tree: results/ holding a dataset (the truth), a blind copy, a folder of
    the job's own, the benchmark's logs, and a source file beside results/."""
    if not os.path.isdir(TREES):
        pytest.skip(f"no {TREES} on this machine")
    root = Path(tempfile.mkdtemp(dir=TREES, prefix="jointbench-test-"))
    try:
        for folder, name, text in [
            ("results/datasets", "d.parquet", "the truth"),
            ("results/blind", "d.parquet", "the markers"),
            ("results/estimates/mine", "old.txt", "its own"),
            ("results/logs", "builtin.log", "the benchmark's log"),
            ("src", "code.py", "the code"),
        ]:
            (root / folder).mkdir(parents=True)
            (root / folder / name).write_text(text)
        yield root
    finally:
        shutil.rmtree(root)


def confinement(root: Path) -> landlock.Confinement:
    results = str(root / "results")
    return landlock.Confinement(results, [f"{results}/blind"], [f"{results}/estimates/mine"])


def run_confined(root: Path, command: str, tmp_path: Path) -> tuple[int, str]:
    """``command`` run by bash in ``root`` from a forked child confined to
    :func:`confinement`: its exit status and what it wrote."""
    written = tmp_path / "written"
    child = os.fork()
    if child == 0:
        try:
            out = os.open(written, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
            os.dup2(out, 1)
            os.dup2(out, 2)
            os.chdir(root)
            landlock.confine(confinement(root))
            os.execvp("bash", ["bash", "-c", command])
        finally:
            os._exit(127)
    _, status = os.waitpid(child, 0)
    return os.waitstatus_to_exitcode(status), written.read_text()


@pytest.mark.parametrize(
    "command",
    [
        "cat results/blind/d.parquet",
        "cat src/code.py",
        "ls src",
        "echo new > results/estimates/mine/new.txt && cat results/estimates/mine/new.txt",
        "cat results/estimates/mine/old.txt && ls results/estimates/mine",
        "mkdir -p results/estimates/mine/sub && echo x > results/estimates/mine/sub/x",
        "f=$(mktemp -p /tmp) && echo temporary > $f && cat $f && rm $f",
        "echo beside > src/new.py",
    ],
)
def test_a_confined_process_opens_what_it_is_granted(tree, tmp_path, command):
    status, written = run_confined(tree, command, tmp_path)
    assert status == 0, written


# How the kernel refuses: EACCES, EPERM, and EXDEV for a link between hierarchies that a
# process may not move files between (Landlock's refusal of a link or rename).
REFUSALS = ("Permission denied", "Operation not permitted", "Invalid cross-device link")


@pytest.mark.parametrize(
    "command",
    [
        "cat results/datasets/d.parquet",
        "cat results/blind/../datasets/d.parquet",
        "cat /proc/self/cwd/results/datasets/d.parquet",
        "cd results/estimates/mine && cat ../../datasets/d.parquet",
        "ln -s ../../datasets/d.parquet results/estimates/mine/link && "
        "cat results/estimates/mine/link",
        "ln -s $PWD/results/datasets results/estimates/mine/folder && "
        "cat results/estimates/mine/folder/d.parquet",
        "ln results/datasets/d.parquet results/estimates/mine/hard && "
        "cat results/estimates/mine/hard",
        "cp results/datasets/d.parquet results/estimates/mine/copy",
        "ls results/datasets",
        "ls results",
        "ls .",
        "bash -c 'cat results/datasets/d.parquet'",
        "(setsid cat results/datasets/d.parquet &) ; sleep 0.5; exit 1",
        "echo spoiled >> results/blind/d.parquet",
        "echo new > results/new.txt",
        "echo new > results/datasets/new.txt",
        "rm results/datasets/d.parquet",
        "mv results/estimates/mine/old.txt results/datasets/",
        "cat results/logs/builtin.log",
        "ls results/logs",
        "echo its log > results/logs/mine.log",
        "echo truncated > results/logs/builtin.log",
    ],
)
def test_a_confined_process_opens_nothing_else_under_the_hidden_folder(tree, tmp_path, command):
    """Whatever the path (``..``, ``/proc/self/cwd``, a link it makes in its own folder), by
    itself, a child or a daemon: refused by the kernel, which judges the object opened."""
    status, written = run_confined(tree, command, tmp_path)
    assert status != 0, written
    assert any(refusal in written for refusal in REFUSALS), written
    assert (tree / "results" / "datasets" / "d.parquet").read_text() == "the truth"
    assert (tree / "results" / "blind" / "d.parquet").read_text() == "the markers"
    assert (tree / "results" / "logs" / "builtin.log").read_text() == "the benchmark's log"


def test_the_entries_beside_are_all_but_the_way_to_the_hidden_folder(tree):
    (tree / "link").symlink_to(tree / "results")
    beside = landlock.entries_beside(str(tree / "results"))
    assert str(tree / "src") in beside
    assert str(tree / "results") not in beside and str(tree) not in beside
    assert str(tree / "link") not in beside  # a link to results/ is no way around it
    assert "/" not in beside and str(Path(TREES).parent) not in beside
    assert not [p for p in beside if p.startswith(str(tree / "results"))]


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("[]", "is not what the workflow writes"),
        ('{"hidden": "/r"}', "is not what the workflow writes"),
        (
            '{"hidden": "r", "readable": [], "writable": []}',
            "a path is not absolute",
        ),
        (
            '{"hidden": "/r", "readable": ["/datasets"], "writable": []}',
            "/datasets does not lie",
        ),
        (
            '{"hidden": "/r", "readable": [], "writable": ["/r/../x"]}',
            "/r/../x does not lie",
        ),
    ],
)
def test_a_confinement_not_the_workflows_is_refused_naming_the_variable(text, named):
    with pytest.raises(ValueError, match=landlock.VARIABLE) as refused:
        landlock.decoded(text)
    assert named in str(refused.value)


def test_the_limited_shell_runs_nothing_without_a_confinement(tmp_path):
    ran = tmp_path / "ran"
    environ = {**os.environ, timelimit.PYTHON_VARIABLE: sys.executable}
    environ[timelimit.LIMIT_VARIABLE] = "60"
    environ.pop(landlock.VARIABLE, None)
    shell = subprocess.run(
        [timelimit.LIMITED_SHELL, "-c", f"touch {ran}"], env=environ, capture_output=True, text=True
    )
    assert shell.returncode == 2
    assert f"{landlock.VARIABLE} is not set" in shell.stderr
    assert not ran.exists()


def test_a_keeper_within_a_confined_job_confines_it_the_same(tree, tmp_path):
    """A job's own limited shell (a script job's long shell() call) is confined again, by the
    entries its keeper handed down, which it could not list itself."""
    # The confinement inherited as the job's keeper left it.
    environ = {timelimit.PYTHON_VARIABLE: sys.executable, timelimit.LIMIT_VARIABLE: "60"}
    inner = f"cat results/blind/d.parquet; cat results/datasets/d.parquet; cat {tree}/src/code.py"
    command = f"{timelimit.LIMITED_SHELL} -c '{inner}'"
    status, written = run_confined(
        tree, " ".join(f"{k}='{v}'" for k, v in environ.items()) + f" {command}", tmp_path
    )
    assert status == 0, written
    assert written.startswith("the markers") and written.endswith("the code"), written
    assert "cat: results/datasets/d.parquet: Permission denied" in written


def test_where_the_kernel_has_no_landlock_nothing_is_confined(tree, monkeypatch):
    monkeypatch.setattr(landlock, "abi_version", lambda: 0)
    assert landlock.confine(confinement(tree)) is False
    with landlock.temporary_folder(confinement(tree)) as own:
        assert own is None


def test_a_job_starts_however_many_entries_lie_beside_its_checkout(tree, tmp_path):
    """The limited shell, as Snakemake starts it, runs its command though the folder holding
    results/ holds thousands of entries (a shared temporary folder): what the keeper lists of
    them to confine itself is not handed down in the environment, whose single variable Linux
    bounds (an exec given a longer one fails with "Argument list too long")."""
    for number in range(1500):
        (tree / f"an-entry-beside-the-checkout-with-a-long-name-{number:04d}-{'x' * 60}").touch()
    environ = {**os.environ, timelimit.PYTHON_VARIABLE: sys.executable}
    environ[timelimit.LIMIT_VARIABLE] = "60"
    environ[landlock.VARIABLE] = landlock.encoded(confinement(tree))
    shell = subprocess.run(
        [timelimit.LIMITED_SHELL, "-c", "cat results/blind/d.parquet"],
        env=environ,
        cwd=tree,
        capture_output=True,
        text=True,
    )
    assert (shell.returncode, shell.stdout) == (0, "the markers"), shell.stderr[-2000:]


def test_a_confinement_longer_than_an_environment_variable_may_be_is_refused():
    """Every job of the run would fail to start: refused as it is encoded, before any job,
    saying how long it is and what to do."""
    folders = [f"/r/{'folder-' * 10}{number}" for number in range(2000)]
    with pytest.raises(ValueError, match=landlock.VARIABLE) as refused:
        landlock.encoded(landlock.Confinement("/r", [], folders))
    assert "2000 folders" in str(refused.value)
    assert "fewer folders" in str(refused.value)
    assert landlock.decoded(landlock.encoded(landlock.Confinement("/r", [], folders[:9])))


def test_a_confinement_claimed_inherited_by_a_process_not_confined_is_refused(tree, tmp_path):
    """A keeper handed a confinement marked inherited adds nothing to its own: one that can
    list the hidden folder (started unconfined) runs nothing."""
    ran = tmp_path / "ran"
    environ = {**os.environ, timelimit.PYTHON_VARIABLE: sys.executable}
    environ[timelimit.LIMIT_VARIABLE] = "60"
    claimed = confinement(tree)._replace(inherited=True)
    environ[landlock.VARIABLE] = landlock.encoded(claimed)
    shell = subprocess.run(
        [timelimit.LIMITED_SHELL, "-c", f"touch {ran}"], env=environ, capture_output=True, text=True
    )
    assert shell.returncode == 2, shell.stderr
    assert "says this process is confined already" in shell.stderr
    assert not ran.exists()
