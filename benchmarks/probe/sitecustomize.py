"""Per-process resource use for benchmarks/scaling.py, loaded by Python at start-up.

When benchmarks/scaling.py puts this folder on PYTHONPATH and names a folder in
JOINTBENCH_RUSAGE_DIR, every Python process of a Snakemake run (Snakemake itself, each job's
script, an external estimator's interpreter) writes one JSON record there as it exits: its
wall time, CPU time and peak resident memory as the kernel counted them, and which job it was.
The rule files are not changed, and the numbers are exact (no polling). Without
JOINTBENCH_RUSAGE_DIR this module does nothing.
"""

import atexit
import json
import os
import resource
import sys
import time

_FOLDER = os.environ.get("JOINTBENCH_RUSAGE_DIR")


def _process_start() -> float:
    """When this process began (epoch seconds), from the kernel; now if that is unreadable."""
    try:
        with open("/proc/self/stat") as stat:
            # Field 22 counts clock ticks since boot; the command name before it may hold spaces.
            ticks = int(stat.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/stat") as boot:
            booted = next(int(line.split()[1]) for line in boot if line.startswith("btime"))
        return booted + ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, StopIteration):
        return time.time()


def _peak_rss_mb() -> float:
    """This program's peak resident memory (MB) since it was exec'd.

    Not getrusage's ru_maxrss: that survives exec, so a job forked from the 200 MB Snakemake
    process would report at least 200 MB. VmHWM belongs to the current address space only.
    """
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("/proc/self/status has no VmHWM line")


def _job() -> dict:
    """The Snakemake job this process runs, when it is a rule's script; else its command line."""
    job = getattr(sys.modules.get("__main__"), "snakemake", None)
    rule = getattr(job, "rule", None)
    if isinstance(rule, str):
        return {"rule": rule, "wildcards": {k: str(v) for k, v in job.wildcards.items()}}
    return {"rule": None, "wildcards": {}}


def _record(start: float) -> None:
    end = time.time()
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    record = {
        "pid": os.getpid(),
        "ppid": os.getppid(),
        "argv": sys.argv,
        **_job(),
        "start": start,
        "end": end,
        "wall_s": end - start,
        # Own and waited-for children apart: Snakemake's children are the jobs, recorded too.
        "cpu_s": own.ru_utime + own.ru_stime,
        "children_cpu_s": children.ru_utime + children.ru_stime,
        "peak_rss_mb": _peak_rss_mb(),
        # Largest of the waited-for children (kilobytes on Linux), for jobs that start their own.
        "children_peak_rss_mb": children.ru_maxrss / 1024,
    }
    path = os.path.join(_FOLDER, f"{os.getpid()}-{int(start * 1e6)}.json")
    with open(path, "w") as out:
        json.dump(record, out)


if _FOLDER:
    atexit.register(_record, _process_start())
