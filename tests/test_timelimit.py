"""The time limit of an external estimator's job (jointbench.running.timelimit): a program past
it is stopped with every process it started, whatever it does to stay; one within it runs as it
would without; the limit is checked before any job.

The end-to-end case, a user's program that never ends in a run, is in tests/test_extension.py.
"""

from __future__ import annotations

import contextlib
import math
import os
import pty
import select
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from snakemake.shell import shell as snakemake_shell
from snakemake.utils import validate
from workflow_copy import ROOT, SNAKEMAKE

from jointbench.configuration import config as jb_config
from jointbench.running import landlock, timelimit

# Long enough for bash to start and write a pid file on a loaded machine, short for the tests.
LIMIT_S = 1.5
GRACE_S = 0.5
# A program that outlives its test by far: past the deadlines below, it was not stopped.
FOREVER = "sleep 300"
# What the workflow lets a job open under a results/ (landlock): here, the repository's, which
# the jobs of these tests do not read.
CONFINED = landlock.encoded(landlock.Confinement(str(ROOT / "results"), [], []))
# What Snakemake puts before the command of a job whose shell is named bash, as the limited
# shell is.
SNAKEMAKES_PREFIX = "set -euo pipefail; "


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting for its parent to reap it has ended)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"


def pids(path: Path) -> list[int]:
    return [int(line) for line in path.read_text().split()]


@contextlib.contextmanager
def ended_after(written: Path, kill=os.killpg) -> Iterator[None]:
    """Run the block, then kill (SIGKILL) each process, or group, whose pid the job wrote to
    ``written``: a test that fails leaves nothing of its job running."""
    try:
        yield
    finally:
        for left in pids(written) if written.exists() else []:
            with contextlib.suppress(ProcessLookupError):
                kill(left, signal.SIGKILL)


def timed(argv: list[str], limit_s: float = LIMIT_S) -> tuple[int | None, float]:
    start = time.monotonic()
    status = timelimit.run_limited(argv, limit_s, GRACE_S)
    return status, time.monotonic() - start


def test_a_program_past_the_limit_is_stopped_at_it():
    status, seconds = timed(["bash", "-c", FOREVER])
    assert status is None
    assert LIMIT_S <= seconds < LIMIT_S + GRACE_S


def test_a_program_that_ends_just_under_the_limit_keeps_its_status():
    status, seconds = timed(["bash", "-c", "sleep 1.0; exit 3"])
    assert status == 3
    assert 1.0 <= seconds < LIMIT_S


def test_a_program_ended_by_a_signal_of_its_own_says_which():
    status, _ = timed(["bash", "-c", "kill -SEGV $$"])
    assert status == -signal.SIGSEGV


def with_child(
    tmp_path: Path, program: str, child: str = FOREVER
) -> tuple[int | None, float, bool]:
    """``program`` (bash, ``{child}`` standing for ``child`` started in the background, its
    pid written) run under the limit: its status, its seconds and whether the child still
    runs."""
    written = tmp_path / "pids"
    child = f"{child} & echo $! > {written}"
    status, seconds = timed(["bash", "-c", program.format(child=child)])
    (pid,) = pids(written)
    return status, seconds, alive(pid)


def test_a_child_that_keeps_running_is_stopped_with_its_parent(tmp_path):
    """Parent and child both past the limit: the group goes, the child with it."""
    status, _, running = with_child(tmp_path, f"{{child}}; {FOREVER}")
    assert status is None
    assert not running


def test_a_child_left_behind_by_a_program_that_ended_is_stopped(tmp_path):
    """The program ends at once and leaves a child running: the job does not end with part of
    it still running, outside any limit."""
    status, seconds, running = with_child(tmp_path, "{child}")
    assert status == 0
    assert seconds < LIMIT_S
    assert not running


def test_a_program_that_ignores_sigterm_is_killed_after_the_grace(tmp_path):
    status, seconds, running = with_child(tmp_path, "trap '' TERM; {child}; wait")
    assert status is None
    assert LIMIT_S + GRACE_S <= seconds < LIMIT_S + GRACE_S + 1.0
    assert not running


def test_a_child_that_ignores_sigterm_after_its_parent_ended_is_killed(tmp_path):
    """The parent ends on SIGTERM, its child ignores it: SIGKILL still reaches the child."""
    status, _, running = with_child(tmp_path, f"(trap '' TERM; {{child}}; wait); {FOREVER}")
    assert status is None
    assert not running


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
@pytest.mark.parametrize(
    # Half a second for the child to have left the group before its parent ends.
    ("program", "stopped"),
    [("{child}; sleep 0.5", False), (f"{{child}}; {FOREVER}", True)],
)
def test_a_child_that_leaves_the_group_is_stopped_when_its_parent_has_ended(
    tmp_path, program, stopped
):
    """A daemon: the child starts a session of its own, out of the group the limit stops;
    once the program has ended by itself or been stopped, the child is stopped too."""
    status, _, running = with_child(tmp_path, program, child=f"setsid {FOREVER}")
    assert status == (None if stopped else 0)
    assert not running


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_a_grandchild_that_left_the_group_of_a_child_that_left_is_stopped(tmp_path):
    """Two removes: a child in a session of its own starts its own child in another."""
    written = tmp_path / "pids"
    inner = f"setsid {FOREVER} & echo $! > {written}; {FOREVER}"
    status, _ = timed(["bash", "-c", f"setsid bash -c '{inner}' & sleep 0.5"])
    assert status == 0
    (grandchild,) = pids(written)
    assert not alive(grandchild)


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_a_process_of_the_job_that_changed_its_user_leaves_the_rest_stopped(tmp_path, monkeypatch):
    """A process of the job that is no longer this user's (a command run through sudo) cannot
    be signalled: the kernel refuses with EPERM. The rest of the job is stopped all the same,
    and the keeper goes on to end, rather than failing with a traceback and leaving the
    processes not yet signalled running without a limit."""
    written = tmp_path / "pids"
    daemons = f"setsid {FOREVER} & echo $! >> {written}; setsid {FOREVER} & echo $! >> {written}"
    kill = os.kill
    with ended_after(written, kill):
        # Faked, as root may signal any process: the first daemon stands for one that changed
        # its user.
        def refused_for_the_first(pid: int, signum: int) -> None:
            if pid == pids(written)[0]:
                raise PermissionError(1, "Operation not permitted")
            kill(pid, signum)

        monkeypatch.setattr(timelimit.os, "kill", refused_for_the_first)
        status, _ = timed(["bash", "-c", f"{daemons}; sleep 0.5"])
        monkeypatch.undo()
        assert status == 0
        _changed_user, other = pids(written)
        end_within([other], 1.0)


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_a_daemon_whose_parent_ends_as_the_job_is_listed_is_sent_sigterm(
    tmp_path, monkeypatch, stopped_as_the_keeper_is
):
    """The SIGTERM to the program's group ends the program while the job's processes are
    listed: a daemon it started, moved to the keeper (the reaper of the job's orphans) after
    the keeper's children were read and before the program's were, is missed by that
    listing, and would end only at the SIGKILL after the grace, its SIGTERM handler never
    run. Here the program always ends at that moment; it stops its keeper (this process)
    itself once the daemon handles SIGTERM."""
    written, termed = tmp_path / "pids", tmp_path / "termed"
    on_sigterm = f'trap "echo TERM > {termed}; exit" TERM'
    daemon = f"setsid bash -c '{on_sigterm}; echo $$ > {written}; {FOREVER} & wait' &"
    ready = f"until [ -s {written} ]; do sleep 0.05; done"
    stopped_groups = []
    signal_group, children = timelimit._signal_group, timelimit._children

    def group_signalled(group: int, signum: int) -> None:
        signal_group(group, signum)
        stopped_groups.append(group)

    def read_once_the_program_has_ended(pid: int) -> list[int]:
        if pid in stopped_groups[:1]:
            end_within([pid], 5)
        return children(pid)

    monkeypatch.setattr(timelimit, "_signal_group", group_signalled)
    monkeypatch.setattr(timelimit, "_children", read_once_the_program_has_ended)
    with pytest.raises(timelimit.Interrupted):
        timed(["bash", "-c", f"{daemon} {ready}; kill -TERM $PPID; {FOREVER}"], limit_s=60)
    assert termed.read_text() == "TERM\n"
    (daemon_pid,) = pids(written)
    assert not alive(daemon_pid)


def test_a_program_that_leaves_orphans_without_end_is_stopped_after_the_grace():
    """A program that ignores SIGTERM and leaves one orphan after another (each a process
    started by a subshell that ends at once, as a daemon starts): every listing of the job
    finds a new one, and the SIGTERM, sent to each process listed until a listing finds none
    new, is not sent for ever; the SIGKILL after the grace ends the program."""
    status, seconds = timed(["bash", "-c", "trap '' TERM; while :; do (sleep 1 &); done"])
    assert status is None
    assert LIMIT_S + GRACE_S <= seconds < LIMIT_S + GRACE_S + 1.0


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_children_that_left_the_group_and_ignore_sigterm_share_one_grace(tmp_path):
    """A program that leaves several daemons behind, each in a session of its own and each
    ignoring SIGTERM: they are stopped together, one grace for all, not one grace each (8
    daemons would hold the job 8 graces past its end, and a hundred, minutes)."""
    written = tmp_path / "pids"
    daemon = f"setsid bash -c 'trap \"\" TERM; echo $$ >> {written}; {FOREVER}' &"
    # Half a second for the daemons to have left the group before the program ends.
    status, seconds = timed(["bash", "-c", f"{daemon * 8} sleep 0.5"])
    assert status == 0
    daemons = pids(written)
    assert len(daemons) == 8
    assert not any(alive(pid) for pid in daemons)
    assert seconds < 0.5 + GRACE_S + 1.0


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_daemons_that_detach_again_and_again_are_stopped_together_under_one_grace(tmp_path):
    """A daemon that detaches twice and more: each level starts the next in a session of its
    own and stays, ignoring SIGTERM, so that a level becomes an orphan of the job only once
    the level above it has ended. Every level is stopped, however deep, and all under one
    grace, not one grace per level."""
    written = tmp_path / "pids"
    levels = 7
    level = tmp_path / "level.sh"
    level.write_text(
        f"trap '' TERM; echo $$ >> {written}\n"
        f'if [ "$1" -gt 1 ]; then setsid bash {level} $(($1 - 1)) & fi\n'
        f"exec {FOREVER}\n"
    )
    # The program ends once every level has started.
    program = (
        f"setsid bash {level} {levels} & "
        f"until [ $(cat {written} 2>/dev/null | wc -l) -ge {levels} ]; do sleep 0.05; done"
    )
    status, seconds = timed(["bash", "-c", program], limit_s=10)
    assert status == 0
    daemons = pids(written)
    assert len(daemons) == levels
    assert not [pid for pid in daemons if alive(pid)]
    assert seconds < GRACE_S + 2.0


def test_a_process_reaped_as_its_threads_are_listed_has_no_children(monkeypatch):
    """A process listed as the job's may end, and be reaped by its parent, just as its
    threads are listed for their children: it has none, rather than the keeper failing as it
    stops the job, and leaving the rest of it running."""
    process = subprocess.Popen(["sleep", "300"])
    threads = f"/proc/{process.pid}/task"
    reaped = []

    def reaped_first(lister):
        def listed(path="."):
            if os.fspath(path) == threads and not reaped:
                process.kill()
                reaped.append(process.wait())
            return lister(path)

        return listed

    monkeypatch.setattr(os, "scandir", reaped_first(os.scandir))
    monkeypatch.setattr(os, "listdir", reaped_first(os.listdir))
    assert timelimit._children(process.pid) == []
    assert reaped == [-signal.SIGKILL]


def limited_shell(command: str, limit: str | None, **popen) -> subprocess.Popen:
    """The limited shell as Snakemake starts it, with the limit (if any) the workflow sets."""
    environ = {**os.environ, timelimit.PYTHON_VARIABLE: sys.executable}
    environ[landlock.VARIABLE] = CONFINED
    environ.pop(timelimit.LIMIT_VARIABLE, None)
    if limit is not None:
        environ[timelimit.LIMIT_VARIABLE] = limit
    return subprocess.Popen(
        [timelimit.LIMITED_SHELL, "-c", command], env=environ, text=True, **popen
    )


# Snakemake writes a command longer than 64 KB to a script, which the job's shell runs with
# Snakemake's own bash (snakemake.shell.MAX_ARG_LEN): a no-op of 70 KB makes a command longer.
LONG = f": {'x' * 70_000}; "


def as_snakemake_runs(command: str, limit: str, tmp_path: Path, monkeypatch) -> int:
    """``command`` run as Snakemake runs a job of an external estimator's (the limited shell
    its resource ``shell_exec``, the limit in the environment the workflow sets): its exit
    status."""
    monkeypatch.setenv(timelimit.PYTHON_VARIABLE, sys.executable)
    monkeypatch.setenv(timelimit.LIMIT_VARIABLE, limit)
    monkeypatch.setenv(landlock.VARIABLE, CONFINED)
    monkeypatch.chdir(tmp_path)  # where Snakemake writes a long command's script
    try:
        snakemake_shell(command, resources={"shell_exec": timelimit.LIMITED_SHELL})
    except subprocess.CalledProcessError as error:
        return error.returncode
    return 0


@pytest.mark.parametrize("length", ["short", "over-64-KB"])
def test_the_limited_shell_runs_a_command_as_snakemakes_bash_does(length, tmp_path, monkeypatch):
    """bash, and Snakemake's prefix for it: a failing step of a pipe fails the command, long
    or short; a long command the job's shell runs from the script Snakemake wrote."""
    out = tmp_path / "out"
    command = f"echo ok >> {out}; false | true; echo not reached >> {out}"
    command = (LONG if length == "over-64-KB" else "") + command
    assert as_snakemake_runs(command, "10", tmp_path, monkeypatch) == 1
    assert out.read_text() == "ok\n"


def test_a_command_over_64_kb_is_stopped_at_the_limit(tmp_path, monkeypatch):
    start = time.monotonic()
    assert as_snakemake_runs(LONG + FOREVER, "1", tmp_path, monkeypatch) == timelimit.EXPIRED
    assert time.monotonic() - start < 1 + timelimit.GRACE_S


def test_a_long_shell_call_of_a_script_job_runs_as_a_short_one(tmp_path, monkeypatch):
    """A ``script:`` job's preamble makes the limited shell Snakemake's shell for the script's
    own ``shell()`` calls: a long one of those runs from its script, under the limit, too."""
    monkeypatch.setattr(snakemake_shell, "_process_args", {})
    snakemake_shell.executable(timelimit.LIMITED_SHELL)
    out = tmp_path / "out"
    command = f"{LONG}echo ok >> {out}; false | true; echo not reached >> {out}"
    assert as_snakemake_runs(command, "10", tmp_path, monkeypatch) == 1
    assert out.read_text() == "ok\n"


@pytest.mark.skipif(shutil.which("perl") is None, reason="no perl on this machine")
def test_a_writer_whose_reader_has_gone_ends_as_under_snakemakes_bash():
    """A program's Python ignores SIGPIPE, and a program it starts inherits that where nothing
    restores it: a writer that does not check its writes (Perl's print, C's printf) piped into
    ``head`` then spins until the limit, and is named as running too long, where Snakemake's
    own shell ends it with SIGPIPE at once."""
    writer = SNAKEMAKES_PREFIX + "perl -e '$| = 1; print qq(y\\n) while 1' | head -n 1"
    shell = limited_shell(writer, "20", stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = shell.communicate(timeout=60)
    assert (shell.returncode, out, err) == (128 + signal.SIGPIPE, "y\n", "")


def test_the_limited_shell_stops_its_command_and_says_so():
    shell = limited_shell(FOREVER, "1", stderr=subprocess.PIPE)
    _, err = shell.communicate(timeout=30)
    assert shell.returncode == timelimit.EXPIRED
    assert "ran past the time limit of 1 s (jobs.external_time_limit_s)" in err


def started(written: Path, processes: int = 1) -> None:
    """Wait until the command has written ``processes`` pids to its pid file ``written``: they
    have started."""
    deadline = time.monotonic() + 20
    while not (written.exists() and len(written.read_text().split()) >= processes):
        assert time.monotonic() < deadline, "the command never started"
        time.sleep(0.05)


def end_within(processes: list[int], seconds: float) -> None:
    """Wait until none of ``processes`` runs, failing the test past ``seconds``."""
    deadline = time.monotonic() + seconds
    while running := [pid for pid in processes if alive(pid)]:
        assert time.monotonic() < deadline, f"{running} run on"
        time.sleep(0.05)


@pytest.mark.parametrize(
    "command",
    [
        # The program itself.
        f"echo $$ > {{written}}; {FOREVER}",
        # A daemon the program started in a session of its own, adopted once it is stopped.
        pytest.param(
            f"setsid {FOREVER} & echo $! > {{written}}; {FOREVER}",
            marks=pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid"),
        ),
    ],
    ids=["its-group", "a-child-that-left-the-group"],
)
def test_the_limited_shell_stopped_from_outside_stops_what_it_ran(command, tmp_path):
    """Ctrl-C, Snakemake cancelling the job or the run killed: neither the program nor a
    daemon it left runs on without the job."""
    written = tmp_path / "pids"
    shell = limited_shell(command.format(written=written), "60")
    started(written)
    shell.send_signal(signal.SIGTERM)
    assert shell.wait(timeout=30) == 128 + signal.SIGTERM
    (process,) = pids(written)
    assert not alive(process)


# A writer and a reader that never reads, each writing its pid: the writer fills the pipe and
# waits on it, as a program whose consumer has stopped reading does.
PIPE_NOBODY_READS = (
    f"(echo $BASHPID >> {{written}}; exec yes) | (echo $BASHPID >> {{written}}; exec {FOREVER})"
)


@pytest.mark.parametrize(
    ("command", "processes"),
    [
        (f"echo $$ > {{written}}; {FOREVER}", 1),
        (PIPE_NOBODY_READS, 2),
        pytest.param(
            f"setsid {FOREVER} & echo $! > {{written}}; {FOREVER}",
            1,
            marks=pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid"),
        ),
    ],
    ids=["its-group", "a-writer-into-a-pipe-nobody-reads", "a-child-that-left-the-group"],
)
def test_the_program_is_stopped_when_its_limited_shell_is_killed(command, processes, tmp_path):
    """Snakemake kills a job's shell with SIGKILL, which nothing can catch, when another job
    of its ``pipe()`` group fails (and so may anyone): what the shell ran does not run on
    without a limit, a writer waiting on a pipe its reader no longer reads among them."""
    written = tmp_path / "pids"
    shell = limited_shell(command.format(written=written), "60")
    started(written, processes)
    shell.kill()
    assert shell.wait(timeout=30) == -signal.SIGKILL
    end_within(pids(written), timelimit.GRACE_S + 5)


# Two limited jobs joined by a pipe(): the producer writes, then works on (sleeps) past its
# consumer, which fails; Snakemake then kills the producer's shell with SIGKILL.
PIPE_GROUP = """
import os, sys
from jointbench.running import landlock, timelimit
os.environ[timelimit.LIMIT_VARIABLE] = "60"
os.environ[timelimit.PYTHON_VARIABLE] = sys.executable
# Its jobs write in the working folder: the folder hidden from them is not above it.
hidden = landlock.Confinement("/jointbench-hides-nothing", [], [])
os.environ[landlock.VARIABLE] = landlock.encoded(hidden)

rule all:
    input: "consumed"

rule produce:
    output: pipe("stream")
    resources: shell_exec=timelimit.LIMITED_SHELL
    shell: "echo $$ > producer; echo data > {output}; exec sleep 300"

rule consume:
    input: "stream"
    output: "consumed"
    resources: shell_exec=timelimit.LIMITED_SHELL
    shell: "cat {input} > /dev/null; sleep 0.5; exit 1"
"""


def test_a_job_of_a_failed_pipe_group_is_stopped_with_its_shell(tmp_path):
    """Snakemake runs the jobs of a ``pipe()`` group together and, when one fails, kills the
    others' shells with SIGKILL: their programs end with them rather than run on, without a
    limit, past the run."""
    (tmp_path / "Snakefile").write_text(PIPE_GROUP)
    # To a file: a program that runs on would hold a pipe's end, and the test, open.
    log = tmp_path / "log"
    with log.open("w") as written:
        run = subprocess.run(
            [SNAKEMAKE, "all", "-j2", "-d", tmp_path, "-s", tmp_path / "Snakefile"],
            stdout=written,
            stderr=subprocess.STDOUT,
            timeout=120,
        )
    assert run.returncode == 1, log.read_text()
    assert "Error in rule consume" in log.read_text()
    end_within(pids(tmp_path / "producer"), timelimit.GRACE_S + 5)


def test_a_program_that_kills_the_process_that_limits_it_is_stopped(tmp_path):
    """The program's parent is the process that holds it to the limit: killed with SIGKILL,
    by the program or anyone, the limited shell adopts what it ran, and stops it."""
    written = tmp_path / "pids"
    shell = limited_shell(f"echo $$ > {written}; kill -KILL $PPID; {FOREVER}", "60")
    assert shell.wait(timeout=30) == 128 + signal.SIGKILL
    end_within(pids(written), 5)


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_a_stop_that_comes_while_the_limited_shell_stops_what_its_keeper_left(tmp_path):
    """The keeper killed (by the program, say), the limited shell stops what it left; told
    to stop meanwhile (Ctrl-C, Snakemake cancelling the job), it finishes the stop, the
    daemon killed after the grace, and ends with the stop's status, rather than with a
    traceback and the daemon running on. Here the daemon, on SIGTERM, stops the shell."""
    written = tmp_path / "pids"
    daemon = tmp_path / "daemon.sh"
    daemon.write_text(
        "trap 'trap \"\" TERM; kill -TERM $1' TERM\n"
        f"echo $$ > {written}\n"
        f"while :; do {FOREVER} & wait; done\n"
    )
    keepers_parent = "$(sed 's/.*) //' /proc/$PPID/stat | cut -d' ' -f2)"
    ready = f"until [ -s {written} ]; do sleep 0.05; done"
    # The daemon's own bash may report its killed loop on stderr; the stderr judged here is
    # the limited shell's.
    program = f"setsid bash {daemon} {keepers_parent} 2>/dev/null & {ready}; kill -KILL $PPID"
    log = tmp_path / "stderr"
    with ended_after(written):
        # To a file: a daemon that runs on would hold a pipe open.
        with log.open("w") as stderr:
            shell = limited_shell(program, "60", stderr=stderr)
            status = shell.wait(timeout=60)
        assert (status, log.read_text()) == (128 + signal.SIGTERM, "")
        (daemon_pid,) = pids(written)
        assert not alive(daemon_pid)


def test_a_stop_that_comes_as_the_keeper_is_waited_for_is_the_shells_status(monkeypatch):
    """Ctrl-C or a cancel just as the wait for the keeper returns: the keeper has ended and
    been waited for, and the limited shell ends with the stop's status, not a traceback."""
    keeper = os.fork()
    if keeper == 0:  # the child: a keeper whose job is done
        os._exit(0)
    waits = []
    wait = os.waitpid

    def waited_then_stopped(pid: int, options: int):
        waits.append(wait(pid, options))
        if len(waits) == 1:
            raise timelimit.Interrupted(signal.SIGINT)
        return waits[-1]

    monkeypatch.setattr(timelimit.os, "waitpid", waited_then_stopped)
    assert timelimit._wait_for_the_keeper(keeper) == 128 + signal.SIGINT


@pytest.fixture
def stopped_as_the_keeper_is():
    """This process's stop signals raise :class:`timelimit.Interrupted`, as the keeper's do;
    the test's own handlers are restored after (a stop's handler ignores the signals once it
    has run)."""
    saved = {signum: signal.getsignal(signum) for signum in timelimit._STOP_SIGNALS}
    for signum in saved:
        signal.signal(signum, timelimit._stops)
    yield
    for signum, handler in saved.items():
        signal.signal(signum, handler)


def test_a_second_stop_that_comes_with_the_first_is_ignored_without_a_word(
    stopped_as_the_keeper_is, monkeypatch
):
    """Two stops at once (the terminal closed: SIGHUP to the run's group, and SIGTERM as
    Snakemake, its parent, ends): the first is taken, the second ignored, as a stop must not
    cut the stop short; and ignored without the interpreter's "Signal 15 ignored due to race
    condition" traceback on the job's stderr, which reads as the limited shell failing."""
    unraisable = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    both = {signal.SIGHUP, signal.SIGTERM}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, both)
    for signum in both:  # to this thread, which holds them until it unblocks them
        signal.pthread_kill(threading.get_ident(), signum)
    with pytest.raises(timelimit.Interrupted):
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)  # both come here
    signal.pthread_sigmask(signal.SIG_BLOCK, [])  # runs the second's handler
    assert [str(each.exc_value) for each in unraisable] == []


def test_a_stop_that_comes_as_the_limited_shell_starts_is_its_status(
    stopped_as_the_keeper_is, monkeypatch
):
    """Ctrl-C or a cancel as the limited shell starts, once it handles the stops and before it
    forks its keeper (as it makes itself the reaper of the job's orphans): nothing of the job
    runs yet, and the shell ends with the stop's status, not a traceback of an uncaught
    :class:`timelimit.Interrupted`."""
    terminal = {signum: signal.getsignal(signum) for signum in (signal.SIGTTOU, signal.SIGTTIN)}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, [])

    def forked() -> int:
        raise AssertionError("the keeper was forked after the stop")

    monkeypatch.setenv(timelimit.LIMIT_VARIABLE, "10")
    monkeypatch.setenv(landlock.VARIABLE, CONFINED)
    # Not on the test's process: told to stop when its parent ends.
    monkeypatch.setattr(timelimit, "_end_with_the_run", lambda parent: None)
    monkeypatch.setattr(timelimit, "_adopt_orphans", lambda: signal.raise_signal(signal.SIGINT))
    monkeypatch.setattr(timelimit.os, "fork", forked)
    try:
        assert timelimit.main(["-c", "true"]) == 128 + signal.SIGINT
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        for signum, handler in terminal.items():
            signal.signal(signum, handler)


def test_a_stop_that_comes_as_the_program_is_started_stops_it(
    stopped_as_the_keeper_is, monkeypatch
):
    """The limited shell killed just as the keeper starts the program (its SIGTERM to the
    keeper arriving while the program is started): the program is stopped with the keeper,
    not left running, without a limit, by a keeper that ended before it knew the program's
    pid."""
    spawned = []
    spawn = os.posix_spawnp

    def spawned_as_stopped(*arguments, **options) -> int:
        spawned.append(spawn(*arguments, **options))
        os.kill(os.getpid(), signal.SIGTERM)
        return spawned[-1]

    monkeypatch.setattr(timelimit.os, "posix_spawnp", spawned_as_stopped)
    try:
        with pytest.raises(timelimit.Interrupted):
            timed(["bash", "-c", FOREVER])
        (program,) = spawned
        assert not alive(program)
    finally:
        for program in spawned:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(program, signal.SIGKILL)


def stop_signals_in(written: Path) -> list[int]:
    """The stop signals set in the signal set a program wrote from its ``/proc/self/status``
    (a line such as ``SigBlk:\t0000000000004000``)."""
    signals = int(written.read_text().split()[1], 16)
    return [signum for signum in timelimit._STOP_SIGNALS if signals >> (signum - 1) & 1]


def test_the_program_starts_with_the_stop_signals_unblocked(tmp_path):
    """However the process that limits it blocks the stop signals (the limited shell blocks
    them across the keeper's fork), the program does not inherit them blocked: a SIGTERM
    would wait, unseen, until the SIGKILL after the grace."""
    written = tmp_path / "blocked"
    held = signal.pthread_sigmask(signal.SIG_BLOCK, timelimit._STOP_SIGNALS)
    try:
        timed(["bash", "-c", f"grep SigBlk /proc/self/status > {written}"])
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
    assert stop_signals_in(written) == []


def test_the_program_starts_with_the_stop_signals_at_their_defaults(
    tmp_path, stopped_as_the_keeper_is
):
    """A keeper told to stop ignores the stop signals from then on (a second must not cut
    its stop short): one told just before it starts the program (the stop held until the
    program's group is known) starts it ignoring them. The program does not inherit them
    ignored, which bash could not undo: the SIGTERM to it would do nothing, and the job end
    only at the SIGKILL after the grace."""
    written = tmp_path / "ignored"
    for signum in timelimit._STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)
    timed(["bash", "-c", f"grep SigIgn /proc/self/status > {written}"])
    assert stop_signals_in(written) == []


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_a_stop_that_comes_as_the_keeper_turns_to_stop_the_job_stops_it_all_the_same(
    tmp_path, monkeypatch, stopped_as_the_keeper_is
):
    """The program has ended, leaving a daemon, and the keeper is told to stop the moment
    it turns from waiting for the program to stopping the rest: the daemon is stopped all
    the same, not left running because the stop came before the stop that holds it."""
    written = tmp_path / "pids"
    stop = timelimit._stop_descendants

    def told_to_stop_first(group: int | None, grace_s: float) -> None:
        os.kill(os.getpid(), signal.SIGTERM)
        stop(group, grace_s)

    monkeypatch.setattr(timelimit, "_stop_descendants", told_to_stop_first)
    with ended_after(written):
        with pytest.raises(timelimit.Interrupted):
            timed(["bash", "-c", f"setsid {FOREVER} & echo $! > {written}; sleep 0.5"])
        (daemon_pid,) = pids(written)
        assert not alive(daemon_pid)


@pytest.mark.skipif(shutil.which("setsid") is None, reason="no setsid on this machine")
def test_a_stop_that_comes_while_the_job_is_stopped_does_not_cut_the_stop_short(
    tmp_path, stopped_as_the_keeper_is
):
    """The keeper told to stop (its limited shell killed) while it stops what a program
    left behind, a daemon in the grace: it finishes the stop, the daemon killed after the
    grace, before it ends, rather than end at once and leave the daemon running without a
    limit. Here the daemon, on the keeper's SIGTERM, stops the keeper (this process)."""
    written = tmp_path / "pids"
    daemon = tmp_path / "daemon.sh"
    daemon.write_text(
        f"trap 'trap \"\" TERM; kill -TERM {os.getpid()}' TERM\n"
        f"echo $$ > {written}\n"
        f"while :; do {FOREVER} & wait; done\n"
    )
    program = f"setsid bash {daemon} & until [ -s {written} ]; do sleep 0.05; done"
    with ended_after(written):
        with pytest.raises(timelimit.Interrupted):
            timed(["bash", "-c", program])
        (daemon_pid,) = pids(written)
        assert not alive(daemon_pid)


def test_a_program_that_cannot_be_started_leaves_a_stop_taken_at_once(stopped_as_the_keeper_is):
    """The stops held while the program is started are taken at once again when it cannot
    be: a keeper, or a caller, left holding them would no longer be stopped by Ctrl-C."""
    with pytest.raises(FileNotFoundError):
        timelimit.run_limited(["no-such-program-jointbench"], LIMIT_S, GRACE_S)
    with pytest.raises(timelimit.Interrupted):
        signal.raise_signal(signal.SIGTERM)


def test_the_limited_shell_stops_its_command_when_the_run_is_killed(tmp_path):
    """Snakemake killed with SIGKILL: the limited shell it started stops the program rather
    than leave it running without a limit."""
    written = tmp_path / "pids"
    environ = {**os.environ, timelimit.PYTHON_VARIABLE: sys.executable}
    environ[timelimit.LIMIT_VARIABLE] = "60"
    environ[landlock.VARIABLE] = CONFINED
    # A stand-in for Snakemake: a shell that starts the limited shell and waits for it.
    command = f"echo $$ > {written}; {FOREVER}"
    run = subprocess.Popen(
        ["bash", "-c", f"{timelimit.LIMITED_SHELL} -c '{command}'; exit $?"], env=environ
    )
    started(written)
    run.kill()
    run.wait()
    (program,) = pids(written)
    deadline = time.monotonic() + timelimit.GRACE_S + 5
    while alive(program):
        assert time.monotonic() < deadline, "the program runs on after the run was killed"
        time.sleep(0.05)


def on_a_terminal(command: str, limit: str) -> tuple[int, float, str]:
    """The limited shell run as a run started from a terminal starts it, in the terminal's
    foreground process group: its exit status, its seconds and what it wrote there."""
    environ = {**os.environ, timelimit.PYTHON_VARIABLE: sys.executable}
    environ[timelimit.LIMIT_VARIABLE] = limit
    environ[landlock.VARIABLE] = CONFINED
    start = time.monotonic()
    pid, terminal = pty.fork()
    if pid == 0:  # the child: a session of its own, the terminal its controlling one
        try:
            os.execve(timelimit.LIMITED_SHELL, [timelimit.LIMITED_SHELL, "-c", command], environ)
        finally:
            os._exit(127)
    written = b""
    while True:
        select.select([terminal], [], [], 60)
        try:
            chunk = os.read(terminal, 4096)
        except OSError:  # the terminal closed: every process on it ended
            break
        if not chunk:
            break
        written += chunk
    _, status = os.waitpid(pid, 0)
    os.close(terminal)
    return os.waitstatus_to_exitcode(status), time.monotonic() - start, written.decode()


def test_a_program_that_sets_the_terminal_runs_as_it_would_without_the_limit():
    """A program of its own process group, as the limit puts it, is out of the terminal's
    foreground: setting the terminal (stty, a pager, a prompt) would stop it (SIGTTOU) until
    the limit, which would then name a program that had not run as running too long."""
    status, seconds, written = on_a_terminal("stty -echo; stty echo; echo set", "20")
    assert (status, written.split()) == (0, ["set"])
    assert seconds < 10


def test_a_program_that_reads_the_terminal_fails_at_once_rather_than_at_the_limit():
    """Reading the terminal (SIGTTIN) would stop it until the limit too: the read fails."""
    status, seconds, written = on_a_terminal(SNAKEMAKES_PREFIX + "read answer; echo answered", "20")
    assert status == 1 and "answered" not in written
    assert seconds < 10


@pytest.mark.parametrize("limit", [None, "0", "-1", "ten", "nan", "inf", "1e9"])
def test_the_limited_shell_runs_nothing_without_a_limit(limit, tmp_path):
    ran = tmp_path / "ran"
    shell = limited_shell(f"touch {ran}", limit, stderr=subprocess.PIPE)
    _, err = shell.communicate(timeout=30)
    assert shell.returncode == 2
    assert timelimit.LIMIT_VARIABLE in err
    assert not ran.exists()


def test_the_expired_message_names_the_rule_the_job_the_limit_and_the_key():
    wildcards = {"study": "cmc", "condition": "marker_set-M__rom_deg-5__noise_mm-1.0"}
    message = timelimit.expired_message("estimate_centroid", wildcards, 2.5)
    assert message.startswith(
        "rule estimate_centroid (study=cmc, condition=marker_set-M__rom_deg-5__noise_mm-1.0): "
    )
    assert "time limit of 2.5 s" in message
    assert message.endswith("raise jobs.external_time_limit_s in the config")


@pytest.mark.parametrize("limit_s", [1.0, 59.0, 3600.0, timelimit.MAX_LIMIT_S])
def test_a_clusters_runtime_outlasts_the_limit_and_its_grace(limit_s):
    """SLURM kills a job past its runtime without naming the limit: the limit comes first."""
    minutes = timelimit.runtime_minutes(limit_s)
    assert isinstance(minutes, int)
    assert minutes * 60 >= limit_s + timelimit.GRACE_S + 60


# ----------------------------------------------------------------------------- the config


def config_with_limit(value: object) -> dict:
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    config.setdefault("jobs", {})["external_time_limit_s"] = value
    return config


def checked_limit(config: dict) -> float:
    """The limit of ``config`` as the workflow takes it as it loads: the schema (whose defaults
    Snakemake's validation fills in), then the limit's own check."""
    jb_config.check_schema(config)
    validate(config, str(jb_config.SCHEMA_PATH))
    return timelimit.configured_limit(config)


def test_the_shipped_config_and_the_schema_agree_on_the_default():
    shipped = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    assert checked_limit(shipped) == 3600
    del shipped["jobs"]
    assert checked_limit(shipped) == 3600


@pytest.mark.parametrize(
    "value", [0, -1, -0.5, "30", "ten", True, None, math.nan, math.inf, 1e9, [30]]
)
def test_a_limit_that_is_no_positive_number_of_seconds_stops_the_run_naming_the_key(value):
    with pytest.raises(ValueError, match=r"jobs[./]external_time_limit_s"):
        checked_limit(config_with_limit(value))


@pytest.mark.parametrize("value", [0.5, 3, 3600, timelimit.MAX_LIMIT_S])
def test_a_positive_limit_up_to_a_week_is_taken(value):
    assert checked_limit(config_with_limit(value)) == value
