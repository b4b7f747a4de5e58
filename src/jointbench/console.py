"""The workflow's console: one line per job (its rule's ``message``), Snakemake's progress line,
and none of the scheduler's chatter.

Snakemake 9 writes every console line through the ``DefaultStreamHandler`` of its logger;
:func:`install` gives that handler a filter and a formatter. Snakemake's log file under
``.snakemake/log/`` keeps every line: only the console is made calm.
"""

from __future__ import annotations

import logging

__all__ = ["STREAM_HANDLER", "install", "job_line", "shown"]

#: The name Snakemake gives its console handler.
STREAM_HANDLER = "DefaultStreamHandler"

# Scheduler messages, one or two per job, that say nothing the job lines and progress do not.
_CHATTER = ("Select jobs to execute...", "Execute ")


def _event(record: logging.LogRecord) -> str:
    event = getattr(record, "event", None)
    return str(getattr(event, "value", event) or "")


def shown(record: logging.LogRecord) -> bool:
    """Whether the console shows ``record``: not a job's "Finished jobid" line (the progress
    line follows it), nor a target rule's job, nor the scheduler's "Select jobs"/"Execute n
    jobs" lines."""
    if _event(record) in ("job_finished", "job_started"):
        return False
    if _event(record) == "job_info" and not getattr(record, "rule_msg", None):
        # A target rule (``all``) has no message and nothing to say.
        return bool(getattr(record, "output", None))
    message = record.msg if isinstance(record.msg, str) else ""
    return not message.startswith(_CHATTER)


def job_line(record: logging.LogRecord) -> str:
    """A job's one console line: its rule's ``message``, else the rule and its wildcards."""
    message = getattr(record, "rule_msg", None)
    if message:
        return str(message)
    wildcards = getattr(record, "wildcards", None) or {}
    details = ", ".join(f"{k}={v}" for k, v in dict(wildcards).items())
    return f"{getattr(record, 'rule_name', 'job')}" + (f" ({details})" if details else "")


class _JobLines(logging.Formatter):
    """Snakemake's formatter, with a job's multi-line block replaced by :func:`job_line`; a dry
    run lists each job in full (rule, wildcards, files: what would run), its message below."""

    def __init__(self, base: logging.Formatter | None, dry_run: bool = False):
        super().__init__()
        self.base = base or logging.Formatter()
        self.dry_run = dry_run

    def format(self, record: logging.LogRecord) -> str:
        if _event(record) != "job_info":
            return self.base.format(record)
        block = getattr(self.base, "_format_job_info", None)
        if self.dry_run and block is not None:
            return "\n".join([*block(record.__dict__), f"    message: {job_line(record)}"])
        return job_line(record)


class _Calm(logging.Filter):
    """:func:`shown` for one handler; before a job's line it marks the last line as a job's,
    so that Snakemake does not write a blank line before each job."""

    def __init__(self, handler: logging.Handler):
        super().__init__()
        self.handler = handler

    def filter(self, record: logging.LogRecord) -> bool:
        if _event(record) == "job_info" and hasattr(self.handler, "last_msg_was_job_info"):
            self.handler.last_msg_was_job_info = True
        return shown(record)


def install(logger: logging.Logger) -> None:
    """Make Snakemake's console handler on ``logger`` calm (see the module doc); a logger
    without that handler (a logger plugin writes the console) is left as it is."""
    for handler in logger.handlers:
        if handler.name == STREAM_HANDLER and not isinstance(handler.formatter, _JobLines):
            dry_run = any(getattr(f, "dryrun", False) for f in handler.filters)
            handler.addFilter(_Calm(handler))
            handler.setFormatter(_JobLines(handler.formatter, dry_run))
