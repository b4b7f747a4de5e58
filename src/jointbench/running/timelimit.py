"""The time limit of an external estimator's job: its program, whatever its language, runs in a
process group of its own and is stopped, with every process it started, once the run's limit
(``jobs.external_time_limit_s``) has passed.

Snakemake sets no time limit on a local job, so the workflow gives every rule of the user's the
resource ``shell_exec`` (workflow/rules/common.smk): Snakemake then runs the job's command,
``shell:`` or ``script:``, as ``limited/bash -c COMMAND`` (the folder beside this file), which
runs this file with the project's interpreter. It reads the limit from the environment the
workflow sets when it loads, so that every job of a run has the same, and it imports nothing
but the standard library: it starts before the user's program, for every job.

The keeper confines the job's reads under ``results/`` first (:mod:`landlock`, beside this
file, which it imports by path when run as a program: the package is not importable there).

Run as a program it exits with the command's status, or :data:`EXPIRED` when the limit
stopped it; the workflow turns that status into an error naming the rule, the job's wildcards,
the limit and the key to raise (:func:`expired_message`).
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib.util
import math
import os
import select
import signal
import sys
import time
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

if __package__:
    from jointbench.running import landlock
else:
    # Run as a program by limited/bash (``python -I -S``), where the package cannot be
    # imported: its sibling module, by path.
    _SIBLING = os.path.join(os.path.dirname(os.path.abspath(__file__)), "landlock.py")
    _SPEC = importlib.util.spec_from_file_location("landlock", _SIBLING)
    landlock = importlib.util.module_from_spec(_SPEC)
    _SPEC.loader.exec_module(landlock)

#: The config key, under ``jobs``, of the limit [s] of each job of an external estimator: its
#: path and its text.
KEY_PATH = ("jobs", "external_time_limit_s")
KEY = ".".join(KEY_PATH)
#: The environment variables the workflow sets when it loads: the limit [s] and the interpreter
#: that runs this file (:data:`LIMITED_SHELL`).
LIMIT_VARIABLE = "JOINTBENCH_TIME_LIMIT_S"
PYTHON_VARIABLE = "JOINTBENCH_PYTHON"
#: The shell ``shell_exec`` names, in a folder beside this file: named bash, as Snakemake gives
#: its prefix (``set -euo pipefail; ``) to a shell of that name alone, and to the script it
#: writes for a command longer than a command line may be (64 KB) too.
LIMITED_SHELL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "limited", "bash")
#: The exit status of a command the limit stopped (GNU ``timeout``'s).
EXPIRED = 124
#: Seconds a stopped group has between SIGTERM (to write what it must, or clean up) and SIGKILL.
GRACE_S = 5.0
# How often a stopped group is looked at [s], and how long a killed one is waited for [s].
_POLL_S = 0.05
_KILLED_S = 2.0
# The signals Python ignores for itself, which a command would inherit ignored: a writer to a
# pipe whose reader has gone would fail its writes rather than end, and one that does not check
# them would spin until the limit. Restored, as subprocess and a shell do.
_RESTORED_SIGNALS = (signal.SIGPIPE, signal.SIGXFSZ)
# The signals that stop the limited shell from outside: Ctrl-C, a closed terminal, Snakemake
# cancelling the job or ending.
_STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)
# prctl(2)'s option that makes a process the reaper of its descendants' orphans.
_PR_SET_CHILD_SUBREAPER = 36
# prctl(2)'s option that sends this process a signal when its parent ends.
_PR_SET_PDEATHSIG = 1


class Interrupted(Exception):
    """The limited shell was itself told to stop: Ctrl-C, a closed terminal, Snakemake
    cancelling the job, or the run's end (:func:`_end_with_the_run`)."""

    def __init__(self, signum: int):
        super().__init__(f"signal {signum}")
        self.signum = signum


def _a_second_stop(_signum: int, _frame: object) -> None:
    """The handler of a stop signal once a stop has come (:class:`_Stops`): nothing."""


class _Stops:
    """The handler of the stop signals (:data:`_STOP_SIGNALS`): a stop raises
    :class:`Interrupted` where this process is, unless held (:meth:`held`, a step that must
    not be cut short, which raises it once done); in a held step, a wait that a stop may
    cut short takes it (:meth:`taken`). Held in Python rather than in the signal mask, which
    holds them from one thread alone: in a process with others (a library's), the signal
    comes to another, and Python runs the handler all the same."""

    def __init__(self) -> None:
        self.holding = False
        self.came: list[int] = []

    def __call__(self, signum: int, _frame: object) -> None:
        # Once stopping, a second signal (the run's end after a Ctrl-C) must not cut it short.
        # Ignored by a handler, not SIG_IGN: one that came with the first, its handler not yet
        # run, would have the interpreter write "ignored due to race condition" on stderr.
        for each in _STOP_SIGNALS:
            signal.signal(each, _a_second_stop)
        if self.holding:
            self.came.append(signum)
            return
        raise Interrupted(signum)

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Hold a stop that comes in the block, and raise it as :class:`Interrupted` once the
        block has ended (unless it raised; in an enclosing held block, once that has)."""
        holding, self.holding = self.holding, True
        try:
            yield
        finally:
            self.holding = holding
        if self.came and not holding:
            raise Interrupted(self.came.pop())

    @contextlib.contextmanager
    def taken(self) -> Iterator[None]:
        """Raise a stop as :class:`Interrupted` as it comes in the block, and one held
        before it at once."""
        holding, self.holding = self.holding, False
        try:
            if self.came:
                raise Interrupted(self.came.pop())
            yield
        finally:
            self.holding = holding


_stops = _Stops()


def group_alive(group: int) -> bool:
    """Whether any process is left in the process group ``group`` (a zombie counts until its
    parent reaps it: :func:`run_limited` reaps the group's)."""
    try:
        os.killpg(group, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        # A process of the group that is no longer ours (it changed its user): still there.
        return True
    return True


def _prctl(option: int, value: int) -> None:
    """prctl(2) where there is one (Linux); elsewhere nothing."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(option, value, 0, 0, 0)


def _adopt_orphans() -> None:
    """Make this process the reaper of its descendants' orphans (Linux), so that a child the
    program leaves behind is reaped here once stopped, rather than by a PID 1 that may never
    reap it (a container's), its zombie keeping the group alive."""
    _prctl(_PR_SET_CHILD_SUBREAPER, 1)


def _end_with_the_run(parent: int) -> None:
    """Be told with SIGTERM when ``parent``, the process that started this one, ends (Linux),
    even killed with SIGKILL: the limited shell is told when Snakemake ends, and stops the
    command rather than leave it running without a limit; the keeper is told when the
    limited shell ends. The limited shell stays in the run's process group, which Ctrl-C and a
    closed terminal signal, and passes those on (:func:`main`)."""
    _prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
    if os.getppid() != parent:  # it ended before it could tell
        raise Interrupted(signal.SIGTERM)


class _Group:
    """The process group of a command started in a group of its own, ``leader`` its pid;
    ``status`` the leader's exit status once reaped (negative: the signal that ended it)."""

    def __init__(self, leader: int):
        self.leader = leader
        self.status: int | None = None

    def reap(self) -> None:
        """Reap every ended process of the group that is this process's child."""
        while True:
            try:
                ended = os.waitid(os.P_PGID, self.leader, os.WEXITED | os.WNOHANG)
            except ChildProcessError:
                return
            if ended is None:
                return
            if ended.si_pid == self.leader:
                killed = ended.si_code in (os.CLD_KILLED, os.CLD_DUMPED)
                self.status = -ended.si_status if killed else ended.si_status

    def wait(self, within_s: float) -> bool:
        """Whether the leader ends within ``within_s`` [s]: woken as it ends where the system
        gives a process a file descriptor (Linux), so that a job of milliseconds is not held
        for a polling interval; polled elsewhere."""
        try:
            ends = os.pidfd_open(self.leader)
        except (AttributeError, OSError):
            return _until(self._leader_reaped, within_s)
        try:
            select.select([ends], [], [], within_s)
        finally:
            os.close(ends)
        return self._leader_reaped()

    def _leader_reaped(self) -> bool:
        self.reap()
        return self.status is not None


def _until(done, within_s: float) -> bool:
    """Whether ``done()`` is true within ``within_s`` [s], asked every :data:`_POLL_S`."""
    deadline = time.monotonic() + within_s
    while True:
        if done():
            return True
        if time.monotonic() >= deadline:
            return False
        time.sleep(_POLL_S)


def _children(pid: int) -> list[int]:
    """The pids of the children of process ``pid``, of every thread of it (Linux's ``/proc``;
    none known elsewhere, nor once it has ended: listed as a job's, it may end, and be
    reaped, before its threads are)."""
    threads = Path(f"/proc/{pid}/task")
    try:
        names = os.listdir(threads)
    except (FileNotFoundError, ProcessLookupError):
        return []
    children = []
    for name in names:
        with contextlib.suppress(OSError):  # a thread that has ended since
            children += [int(child) for child in (threads / name / "children").read_text().split()]
    return children


def _descendants() -> list[int]:
    """The pids of every process descended from this one, at every remove (Linux's ``/proc``;
    none known elsewhere). A process that left its group, or its session, is still a
    descendant; one whose parent ended is this process's child (``_adopt_orphans``)."""
    found = []
    parents = [os.getpid()]
    while parents:
        children = _children(parents.pop())
        found += children
        parents += children
    return found


def _reap_children() -> None:
    """Reap every ended child of this process (an adopted orphan among them)."""
    with contextlib.suppress(ChildProcessError):
        while os.waitid(os.P_ALL, 0, os.WEXITED | os.WNOHANG) is not None:
            pass


def _signal_descendants(group: int | None, signum: int, within_s: float) -> None:
    """Send ``signum`` to the command's process ``group`` (if any; where no descendant is
    known, it is the job) and to every descendant of this process, listed again until a
    listing finds none not yet sent it, for up to ``within_s`` [s].

    One listing is not enough: a process whose parent ends as the job is listed (the signal
    ends it) is moved to this process after this process's children were read and before its
    parent's were, and that listing misses it; the next finds it here. A process started
    while the job is listed is sent the signal too; one started after (a process's own
    clean-up on SIGTERM) is not. Bounded, as a job that leaves orphans faster than it is
    listed would be listed for ever."""
    if group is not None:
        _signal_group(group, signum)
    deadline = time.monotonic() + within_s
    sent: set[int] = set()
    while unsent := set(_descendants()) - sent:
        for pid in unsent:
            with _unreachable_passed():
                os.kill(pid, signum)
        sent |= unsent
        if time.monotonic() >= deadline:
            return


def _none_left(group: int | None) -> bool:
    """Whether the job has ended: no descendant of this process (its ended children reaped)
    and no process in the command's process ``group`` (if any)."""
    _reap_children()
    return not _descendants() and (group is None or not group_alive(group))


def _stop_descendants(group: int | None, grace_s: float) -> None:
    """Stop every process of the job: every descendant of this process, however many times
    removed and whatever group or session it started (a daemon that detached, and one that
    its daemon detached in turn), and the command's process ``group``, all at once: SIGTERM
    to each (:func:`_signal_descendants`), up to ``grace_s`` [s] from it for them all to
    end, then SIGKILL to whatever is left, listed again until none is (a process started in
    between is listed the next time). One grace for all: levels stopped one after another
    would hold the job a grace for each that ignores SIGTERM.

    A stop that comes meanwhile (the limited shell killed, Ctrl-C) is held until the job is
    stopped, and raised then (:class:`Interrupted`): taken at once, it would end this
    process with the rest of the job running on, without a limit."""
    with _stops.held():
        if _none_left(group):
            return
        graced = time.monotonic() + grace_s
        _signal_descendants(group, signal.SIGTERM, grace_s)
        if _until(lambda: _none_left(group), graced - time.monotonic()):
            return

        def killed() -> bool:
            _signal_descendants(group, signal.SIGKILL, _KILLED_S)
            return _none_left(group)

        # A killed process ends when the kernel next runs it; one that cannot (a read of a
        # dead disk) is past any signal's reach, and the job ends without it.
        _until(killed, _KILLED_S)


def _signal_group(group: int, signum: int) -> None:
    with _unreachable_passed():
        os.killpg(group, signum)


def _unreachable_passed() -> contextlib.AbstractContextManager:
    """Pass over a signal that cannot reach its process: it has ended, or it is no longer
    this user's (a command run through sudo), which the kernel refuses with EPERM. Either
    way the rest of the job must still be signalled: raised, it would end the keeper with
    the processes not yet signalled running on without a limit."""
    return contextlib.suppress(ProcessLookupError, PermissionError)


def run_limited(argv: Sequence[str], limit_s: float, grace_s: float = GRACE_S) -> int | None:
    """Run ``argv`` in a process group of its own for at most ``limit_s`` [s]:
    its exit status (negative: the signal that ended it), or None when the limit stopped it.
    Whatever of it is still running when it ends, is stopped or is stopped from outside
    (:class:`Interrupted`, passed on after) is stopped (:func:`_stop_descendants`): nothing
    of the job outlives it. This process becomes the reaper of the command's orphans
    (``_adopt_orphans``), and every process descended from it is taken as the job's: it
    runs nothing else (the keeper, :func:`_keep`).

    A stop is taken only while the command runs (the wait for it). One that comes as the
    command is started, or as the job is stopped, is held until that is done: taken as the
    command is started, it would end this process with the command's pid unknown, and the
    command running on without a limit. The command starts with the stops unblocked and at
    their defaults, whatever this process does with them: one it inherited blocked would
    wait, unseen, and one inherited ignored (a caller's) would do nothing, until the
    SIGKILL."""
    _adopt_orphans()
    job_mask = signal.pthread_sigmask(signal.SIG_BLOCK, []) - set(_STOP_SIGNALS)
    with _stops.held():
        group = _Group(
            os.posix_spawnp(
                argv[0],
                list(argv),
                os.environ,
                setpgroup=0,
                setsigmask=job_mask,
                setsigdef=(*_RESTORED_SIGNALS, *_STOP_SIGNALS),
            )
        )
        try:
            with _stops.taken():
                ended = group.wait(limit_s)
        finally:
            _stop_descendants(group.leader, grace_s)
    return group.status if ended else None


#: The longest limit [s], a week: a cluster's longest partitions allow about that, and a longer
#: one holds a run that never ends for as good as ever.
MAX_LIMIT_S = 7 * 24 * 3600.0


def limit_problem(value: object) -> str | None:
    """What keeps ``value`` from being a limit [s]: not a number (a bool is none), not finite,
    not above 0 or above :data:`MAX_LIMIT_S`, in words; None if nothing."""
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if number and 0 < value <= MAX_LIMIT_S:  # False for NaN
        return None
    return (
        f"{value!r} is not a number of seconds in (0, {MAX_LIMIT_S:g}]: every job of an "
        "external estimator is stopped at it, and none may run without a limit"
    )


def configured_limit(config: Mapping) -> float:
    """The limit [s] ``config`` sets under :data:`KEY` (the schema's default, which the
    workflow's validation fills in, where the files set none); ``ValueError`` naming the key
    when it is no limit (:func:`limit_problem`), which the workflow raises as it loads,
    before any job."""
    section, key = KEY_PATH
    value = config.get(section, {}).get(key)
    problem = limit_problem(value)
    if problem:
        raise ValueError(f"config: {KEY}: {problem}")
    return float(value)


def limit_from(environ: Mapping[str, str]) -> float:
    """The limit [s] the workflow put in ``environ``, or ``ValueError`` saying it is not
    there or not a positive finite number: a job never runs without one."""
    text = environ.get(LIMIT_VARIABLE)
    if text is None:
        raise ValueError(
            f"{LIMIT_VARIABLE} is not set: the workflow sets it from {KEY} when it loads"
        )
    try:
        limit = float(text)
    except ValueError:
        limit = math.nan
    problem = limit_problem(limit)
    if problem:
        raise ValueError(f"{LIMIT_VARIABLE}={text!r}: {problem}")
    return limit


def _seconds(value: float) -> str:
    return f"{value:g} s"


def stopped_line(limit_s: float) -> str:
    """What the limited shell says on its stderr when the limit stopped its command."""
    return (
        f"jointbench: the job's program ran past the time limit of {_seconds(limit_s)} ({KEY}): "
        f"it was stopped with every process it started (SIGTERM, then SIGKILL after "
        f"{_seconds(GRACE_S)})"
    )


def expired_message(rule: str, wildcards: Mapping[str, str], limit_s: float) -> str:
    """The error of a job of ``rule`` (its ``wildcards``, by name) that the limit stopped,
    naming the limit and the key that raises it."""
    job = ", ".join(f"{name}={value}" for name, value in wildcards.items())
    return (
        f"rule {rule}{f' ({job})' if job else ''}: its program ran past the time limit of "
        f"{_seconds(limit_s)} for a job of an external estimator and was stopped, with every "
        f"process it started; if it needs longer, raise {KEY} in the config"
    )


def runtime_minutes(limit_s: float) -> int:
    """The ``runtime`` [min] a cluster gives a job limited to ``limit_s`` [s]: the limit, the
    grace of a stopped group and a minute for Snakemake to start on the node, so that the
    limit, which names the job and the key, stops a program before the cluster's does."""
    return math.ceil((limit_s + GRACE_S) / 60) + 1


def main(argv: Sequence[str], environ: Mapping[str, str] = os.environ) -> int:
    """``limited/bash ARGUMENTS``: bash run with ``ARGUMENTS`` (``-c COMMAND``, or a script
    Snakemake wrote for a command too long for a command line) under the limit in
    ``environ``, confined to what it may open there (:mod:`landlock`), by a keeper
    (:func:`_keep`) in a process group of its own, which this process waits for. Whichever
    of the two is killed, even with SIGKILL, the other stops the job: the keeper is told when
    this process ends (``_end_with_the_run``), and this process adopts and stops what a
    killed keeper leaves."""
    try:
        limit = limit_from(environ)
        confined = landlock.decoded(landlock.text_from(environ))
        landlock.check_inherited(confined)
    except ValueError as error:
        print(f"jointbench: {error}", file=sys.stderr)
        return 2
    # A stop before the fork finds nothing of the job running: its status, not a traceback.
    try:
        _ready_to_pass_stops_on()
    except Interrupted as stopped:
        return 128 + stopped.signum
    shell = os.getpid()
    with landlock.temporary_folder(confined):
        keeper = os.fork()
        if keeper == 0:
            _exit_keeping(argv, limit, confined, shell)
        return _wait_for_the_keeper(keeper)


def _ready_to_pass_stops_on() -> None:
    """Make the limited shell ready to fork its keeper: its stops handled (:data:`_stops`),
    told when the run ends (``_end_with_the_run``), the reaper of the job's orphans, and its
    stops blocked until each process can pass one on (:class:`Interrupted` for one that came
    before)."""
    for signum in _STOP_SIGNALS:
        signal.signal(signum, _stops)
    # The command's group of its own is out of the terminal's foreground: the stops that
    # brings (setting the terminal, reading it) would hold a program until the limit and have
    # it named as running too long. Ignored, as the command inherits, they are not made: the
    # terminal is set as from the foreground, and a read of it fails.
    for signum in (signal.SIGTTOU, signal.SIGTTIN):
        signal.signal(signum, signal.SIG_IGN)
    _end_with_the_run(os.getppid())
    _adopt_orphans()
    # Blocked until each process is ready to pass a stop on: one arriving between the fork
    # and the wait would end this process without stopping the keeper, and the keeper before
    # it knows its parent.
    signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)


def _exit_keeping(
    argv: Sequence[str], limit_s: float, confined: landlock.Confinement, shell: int
) -> None:
    """End the forked keeper with :func:`_keep`'s status, never returning into the code of
    the process it was forked from (a programming error's traceback printed first)."""
    status = 70  # EX_SOFTWARE: the keeper itself failed
    try:
        status = _keep(argv, limit_s, confined, shell)
    except BaseException:
        sys.excepthook(*sys.exc_info())
    finally:
        sys.stderr.flush()
        os._exit(status)


def _keep(argv: Sequence[str], limit_s: float, confined: landlock.Confinement, shell: int) -> int:
    """The keeper: runs bash with ``argv`` under ``limit_s`` [s] (:func:`run_limited`), in a
    process group of its own, apart from the run's, so that a SIGKILL to the run's group
    (or to the limited shell alone, ``shell``: Snakemake kills the jobs of a ``pipe()`` group
    so when one fails) leaves it to stop the job: its exit status, as a shell's. It confines
    itself first, and so the job, to what ``confined`` grants (:func:`landlock.confine`)."""
    landlock.confine(confined)
    try:
        os.setpgid(0, 0)
        _end_with_the_run(shell)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _STOP_SIGNALS)
        status = run_limited(["bash", *argv], limit_s)
    except Interrupted as stopped:
        return 128 + stopped.signum
    if status is None:
        print(stopped_line(limit_s), file=sys.stderr)
        return EXPIRED
    return _as_a_shell(status)


def _as_a_shell(status: int) -> int:
    """A process's exit ``status`` (negative: the signal that ended it) as a shell gives it
    (128 + the signal)."""
    return 128 - status if status < 0 else status


def _wait_for_the_keeper(keeper: int) -> int:
    """The keeper's exit status, as a shell's (:func:`_keepers_status`). Whatever a keeper
    killed from outside left (its orphans are this process's) is stopped then; a stop that
    comes meanwhile is held until it is, and is the status."""
    try:
        with _stops.held():
            status = _keepers_status(keeper)
            _stop_descendants(None, GRACE_S)
    except Interrupted as stopped:
        status = 128 + stopped.signum
    return status


def _keepers_status(keeper: int) -> int:
    """The keeper's exit status, as a shell's; when this process is told to stop as it
    waits, the keeper is, and is waited for while it stops the job: the stop's status."""
    try:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _STOP_SIGNALS)
        with _stops.taken():
            _, waited = os.waitpid(keeper, 0)
        return _as_a_shell(os.waitstatus_to_exitcode(waited))
    except Interrupted as stopped:
        # The keeper may have ended, and been waited for, just before the stop came.
        with contextlib.suppress(ProcessLookupError, ChildProcessError):
            os.kill(keeper, signal.SIGTERM)
            os.waitpid(keeper, 0)
        return 128 + stopped.signum


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
