"""How long the job of a killed limited shell takes to stop, by the moment of the kill.

The limited shell (jointbench/running/timelimit.py) runs a command that leaves a daemon (a
child in a session of its own) and runs on; it is killed with SIGKILL at each of a range of
moments after its start, many times, and the job's processes are watched until none is left.
A process that does not ignore SIGTERM ends at the keeper's SIGTERM, at once: a stop slower
than ``--slow`` seconds is one the SIGTERM missed (SIGKILL ended it after the grace), and a
process still running past the grace and ``--escaped`` seconds escaped the limit altogether
(it is killed here, by its pid, so that the probe leaves nothing behind). A keeper that
failed (a traceback on its stderr) is counted too::

    PYTHONPATH=src python benchmarks/kill_race.py --delays-ms 0 300 10 --repeats 10

The job's processes are told apart from every other by a number no other command holds: the
seconds of their ``sleep``, unique to each trial.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from jointbench.running import landlock, timelimit

#: The command killed: a daemon left running (``{sleep}`` a sleep unique to the trial), then
#: the program running on.
DAEMON_AND_PROGRAM = "setsid {sleep} & {sleep}"
#: The command killed with ``--ignoring-sigterm``: the daemon ignores SIGTERM, and ends only
#: at the SIGKILL after the grace (every trial slow, none escaped).
DAEMON_IGNORING_SIGTERM = "setsid bash -c \"trap '' TERM; {sleep}\" & {sleep}"


def processes_holding(marker: str) -> list[int]:
    """The pids of the running processes (zombies have no command line) whose command line
    holds ``marker``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        try:
            line = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        if marker.encode() in line:
            found.append(int(entry.name))
    return found


def stopped(
    command: str, delay_s: float, marker: str, give_up_s: float
) -> tuple[float | None, bool]:
    """Start the limited shell with ``command``, kill it with SIGKILL ``delay_s`` [s] after,
    and wait until no process holding ``marker`` runs: the seconds from the kill, or None
    when one still runs ``give_up_s`` [s] after it (those are killed), and whether the keeper
    failed (a traceback on its stderr)."""
    environ = {**os.environ, timelimit.PYTHON_VARIABLE: sys.executable}
    environ[timelimit.LIMIT_VARIABLE] = "600"
    # Its jobs confined as an external estimator's, away from a results/ they do not read.
    hidden = landlock.Confinement(os.path.realpath("results"), [], [])
    environ[landlock.VARIABLE] = landlock.encoded(hidden)
    # To a file: the keeper and the job write on after the shell has been killed.
    with tempfile.TemporaryFile("w+") as stderr:
        shell = subprocess.Popen(
            [timelimit.LIMITED_SHELL, "-c", command], env=environ, stderr=stderr
        )
        time.sleep(delay_s)
        shell.kill()
        killed = time.monotonic()
        shell.wait()
        seconds = None
        while left := processes_holding(marker):
            if time.monotonic() - killed > give_up_s:
                for pid in left:
                    os.kill(pid, signal.SIGKILL)
                break
            time.sleep(0.01)
        else:
            seconds = time.monotonic() - killed
        stderr.seek(0)
        return seconds, "Traceback" in stderr.read()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--delays-ms", nargs=3, type=int, default=[0, 300, 20], metavar=("FROM", "TO", "STEP")
    )
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--slow", type=float, default=1.0, help="a slow stop [s]")
    parser.add_argument("--escaped", type=float, default=3.0, help="past the grace [s]")
    parser.add_argument("--ignoring-sigterm", action="store_true")
    arguments = parser.parse_args(argv)
    template = DAEMON_IGNORING_SIGTERM if arguments.ignoring_sigterm else DAEMON_AND_PROGRAM
    first, last, step = arguments.delays_ms
    give_up_s = timelimit.GRACE_S + arguments.escaped
    print(f"timelimit: {timelimit.__file__}")
    print("| kill after [ms] | trials | slow | escaped | keeper failed | slowest stop [s] |")
    print("|---|---|---|---|---|---|")
    totals = [0, 0, 0, 0]
    trial = 0
    for delay_ms in range(first, last + 1, step):
        stops, failed = [], 0
        for _ in range(arguments.repeats):
            trial += 1
            # A sleep of 300 s and a fraction unique to the trial, in every process of it.
            marker = f"300.{os.getpid()}{trial:05d}"
            command = template.format(sleep=f"sleep {marker}")
            seconds, keeper_failed = stopped(command, delay_ms / 1000, marker, give_up_s)
            stops.append(seconds)
            failed += keeper_failed
        slow = sum(stop is not None and stop > arguments.slow for stop in stops)
        escaped = stops.count(None)
        slowest = max((stop for stop in stops if stop is not None), default=float("nan"))
        counts = [len(stops), slow, escaped, failed]
        print(f"| {delay_ms} | {' | '.join(map(str, counts))} | {slowest:.2f} |", flush=True)
        totals = [total + count for total, count in zip(totals, counts, strict=True)]
    print(f"| all | {' | '.join(map(str, totals))} | |")


if __name__ == "__main__":
    main()
