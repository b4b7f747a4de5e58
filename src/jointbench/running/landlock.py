"""What an external estimator's job may open under ``results/``: Linux's Landlock confines the
job's processes, and every process they start, to the folders the workflow lists.

Landlock is an allow-list over folder hierarchies, checked by the kernel on the object opened
(so neither a symbolic link, ``..`` nor ``/proc/self/cwd`` leads around it). The job keeps
every right outside the hidden folder (``results/``): each entry beside the folders that lead to
it is granted whole. The folders leading to it are granted nothing (a right on a folder holds
for everything below it, the hidden folder too): they can be passed through, not listed nor
written in. Inside the hidden folder only the listed folders are granted: the readable ones
(the blind copies, the programs a rule reads) to be read, the writable ones (where the rules
write, none where the benchmark writes too) wholly; everything else there is neither readable
nor listable.

The workflow writes what to grant into :data:`VARIABLE` as it loads (:func:`encoded`); the
keeper of each job (jointbench/running/timelimit.py) reads it (:func:`text_from`,
:func:`decoded`) and confines itself with it (:func:`confine`) before it starts the job's
command. It imports nothing but the standard library, as the keeper does; where the kernel
has no Landlock (:func:`abi_version` 0: an older Linux, or another system) nothing is
confined, and the workflow says so as it loads.
"""

from __future__ import annotations

import contextlib
import ctypes
import itertools
import json
import os
import shutil
import stat
import sys
import tempfile
from collections.abc import Iterator, Mapping
from typing import NamedTuple

#: The environment variable holding what a job may open under the hidden folder (JSON).
VARIABLE = "JOINTBENCH_CONFINED"

# The file-system rights of Landlock (linux/landlock.h), by the ABI version that added them.
_EXECUTE = 1 << 0
_WRITE_FILE = 1 << 1
_READ_FILE = 1 << 2
_READ_DIR = 1 << 3
_ABI_1 = (1 << 13) - 1  # execute .. make_sym
_REFER = 1 << 13  # ABI 2
_TRUNCATE = 1 << 14  # ABI 3
_IOCTL_DEV = 1 << 15  # ABI 5
#: The rights that apply to a file (the rest apply to a folder's entries).
_FILE_RIGHTS = _EXECUTE | _WRITE_FILE | _READ_FILE | _TRUNCATE | _IOCTL_DEV
#: What a readable folder or file grants: reading and listing it, running a program in it.
READ = _EXECUTE | _READ_FILE | _READ_DIR

# The environment variables that name the temporary folder (Python's tempfile, a compiler's).
_TEMPORARY = ("TMPDIR", "TEMP", "TMP")

# The system calls (the same numbers on every architecture) and their flags.
_CREATE_RULESET = 444
_ADD_RULE = 445
_RESTRICT_SELF = 446
_CREATE_RULESET_VERSION = 1
_RULE_PATH_BENEATH = 1
# prctl(2)'s option that a process and its children gain no privilege by exec (Landlock's
# condition for an unprivileged process).
_PR_SET_NO_NEW_PRIVS = 38


class _RulesetAttr(ctypes.Structure):
    # Its first member alone: the kernel takes a shorter struct as its other members zero
    # (no network right handled, no scope).
    _fields_ = [("handled_access_fs", ctypes.c_uint64)]


class _PathBeneathAttr(ctypes.Structure):
    _pack_ = 1
    _fields_ = [("allowed_access", ctypes.c_uint64), ("parent_fd", ctypes.c_int32)]


def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(None, use_errno=True)


def _syscall(number: int, *arguments) -> int:
    """The system call ``number``'s result; ``OSError`` with its errno when it fails."""
    result = _libc().syscall(ctypes.c_long(number), *arguments)
    if result < 0:
        errno = ctypes.get_errno()
        raise OSError(errno, os.strerror(errno))
    return result


def abi_version() -> int:
    """The Landlock ABI version of this kernel; 0 where there is none (not Linux, a kernel
    older than 5.13, or Landlock not enabled at boot)."""
    if not sys.platform.startswith("linux"):
        return 0
    try:
        return _syscall(_CREATE_RULESET, None, ctypes.c_size_t(0), _CREATE_RULESET_VERSION)
    except OSError:
        return 0


def handled_rights(abi: int) -> int:
    """Every file-system right of Landlock ABI version ``abi`` (a bit mask)."""
    rights = _ABI_1
    if abi >= 2:
        rights |= _REFER
    if abi >= 3:
        rights |= _TRUNCATE
    if abi >= 5:
        rights |= _IOCTL_DEV
    return rights


#: The longest text one environment variable may hold (Linux's ``MAX_ARG_STRLEN``, 32 pages
#: of 4 KiB, less the variable's name, ``=`` and the closing NUL): a program started with a
#: longer one is refused ("Argument list too long"), and every process of a run inherits it.
MAX_LENGTH = 32 * 4096 - len(VARIABLE) - 2


class Confinement(NamedTuple):
    """What a job may open: everything outside the ``hidden`` folder, and under it the
    ``readable`` and ``writable`` folders or files; real, absolute paths.
    ``inherited``: the process holding it is confined to it already (:func:`confine`)."""

    hidden: str
    readable: list[str]
    writable: list[str]
    inherited: bool = False


def encoded(confinement: Confinement) -> str:
    """What :data:`VARIABLE` holds: ``confinement`` as JSON; ``ValueError`` saying what to do
    when that is longer than an environment variable may be (:data:`MAX_LENGTH`): no job
    could start."""
    text = json.dumps(confinement._asdict())
    if len(text.encode()) > MAX_LENGTH:
        count = len(confinement.readable) + len(confinement.writable)
        raise ValueError(
            f"{VARIABLE}, which tells each job of an external estimator what it may open "
            f"under {confinement.hidden}, would name {count} folders or files there "
            f"({len(text.encode())} bytes), more than one environment variable may hold "
            f"({MAX_LENGTH} bytes): no job of the run could start. Have the rules of external "
            "estimators write their files in fewer folders, one per study and estimator "
            "rather than one per condition (README, 'Adding an estimator')"
        )
    return text


def decoded(text: str) -> Confinement:
    """The :class:`Confinement` :data:`VARIABLE`'s ``text`` holds; ``ValueError`` saying
    what is wrong when it is not :func:`encoded`'s, or a path in it is not absolute or does
    not lie under the hidden folder where it must."""
    try:
        confinement = Confinement(**json.loads(text))
    except (ValueError, TypeError) as error:
        raise ValueError(f"{VARIABLE}={text!r} is not what the workflow writes: {error}") from None
    hidden, readable, writable, _ = confinement
    paths = [hidden, *readable, *writable]
    if not all(isinstance(p, str) and os.path.isabs(p) for p in paths):
        raise ValueError(f"{VARIABLE}={text!r}: a path is not absolute")
    outside = [p for p in (*readable, *writable) if not _within(p, hidden)]
    if outside:
        raise ValueError(f"{VARIABLE}: {outside[0]} does not lie under {hidden}")
    return confinement


def _within(path: str, folder: str) -> bool:
    return os.path.commonpath([os.path.normpath(path), folder]) == folder


def _leading_folders(hidden: str) -> list[str]:
    """The folders from ``/`` down to ``hidden``'s parent."""
    folders = []
    folder = os.path.dirname(hidden)
    while True:
        folders.append(folder)
        parent = os.path.dirname(folder)
        if parent == folder:
            return folders[::-1]
        folder = parent


def entries_beside(hidden: str) -> list[str]:
    """Every entry, as it exists now, of the folders leading to ``hidden`` (a real path), but
    those folders and ``hidden`` themselves: what lies outside it. A symbolic link is left
    out: what it leads to lies beside them by its own path, or under ``hidden``."""
    leading = [*_leading_folders(hidden), hidden]
    entries = []
    for folder, next_down in itertools.pairwise(leading):
        for entry in sorted(os.listdir(folder)):
            path = os.path.join(folder, entry)
            if path != next_down and not os.path.islink(path):
                entries.append(path)
    return entries


def granted(confinement: Confinement, beside: list[str], everything: int) -> list[tuple[str, int]]:
    """``(path, rights)`` of every grant of ``confinement``: the rights ``everything`` on each
    entry ``beside`` the folders leading to the hidden one (:func:`entries_beside`), and on
    each writable path; :data:`READ` on each readable one. The folders leading to the hidden
    one are granted nothing (a right on a folder holds for all below it)."""
    return [
        *((p, everything) for p in beside),
        *((p, READ & everything) for p in confinement.readable),
        *((p, everything) for p in confinement.writable),
    ]


def confine(confinement: Confinement) -> bool:
    """Confine this process (its calling thread) and every process it starts from then on to
    ``confinement`` (:func:`granted`): whether it is, False where the kernel has no Landlock.
    A path that does not exist, or is no longer its real path (a link put in its place), is
    not granted; a file is granted a file's rights alone. The entries beside the folders
    leading to the hidden one are listed here, as they are now. A keeper the job starts in
    turn (a script job's long shell() call) is handed ``confinement`` marked inherited in
    :data:`VARIABLE`: it could not list those entries, and has nothing to add, as a process
    cannot leave its confinement, whatever the job writes there; it only checks that it is
    confined (:func:`check_inherited`)."""
    abi = abi_version()
    if abi == 0:
        return False
    check_inherited(confinement)
    if confinement.inherited:
        return True
    beside = entries_beside(confinement.hidden)
    everything = handled_rights(abi)
    attr = _RulesetAttr(everything)
    size = ctypes.c_size_t(ctypes.sizeof(attr))
    ruleset = _syscall(_CREATE_RULESET, ctypes.byref(attr), size, 0)
    try:
        for path, rights in granted(confinement, beside, everything):
            _add_rule(ruleset, path, rights)
        if _libc().prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
            errno = ctypes.get_errno()
            raise OSError(errno, f"prctl(PR_SET_NO_NEW_PRIVS): {os.strerror(errno)}")
        _syscall(_RESTRICT_SELF, ruleset, 0)
    finally:
        os.close(ruleset)
    os.environ[VARIABLE] = encoded(confinement._replace(inherited=True))
    return True


def check_inherited(confinement: Confinement) -> None:
    """``ValueError`` when ``confinement`` is marked inherited but this process can list its
    hidden folder: it is not confined, and the variable was not set by a job's keeper."""
    if not confinement.inherited or not abi_version():
        return
    try:
        os.listdir(confinement.hidden)
    except (PermissionError, FileNotFoundError):
        return
    raise ValueError(
        f"{VARIABLE} says this process is confined already, but it can list "
        f"{confinement.hidden}: it was not set by the keeper of a job"
    )


@contextlib.contextmanager
def temporary_folder(confinement: Confinement) -> Iterator[str | None]:
    """Where the temporary folder (``TMPDIR``, else ``/tmp``) leads to the hidden one (a
    checkout under ``/tmp``), where a confined job may make no file: a folder of the job's own
    in it for the block, named in the environment as the temporary folder, and removed after
    (by the process not confined, which may remove it); None, and nothing done, elsewhere or
    where the kernel has no Landlock."""
    own = _own_temporary_folder(confinement.hidden) if abi_version() else None
    try:
        yield own
    finally:
        if own is not None:
            # What the job left there is its own: a folder that cannot be removed is no error
            # of the job's, and is left to the system's cleaning of its temporary folder.
            shutil.rmtree(own, ignore_errors=True)


def _own_temporary_folder(hidden: str) -> str | None:
    """A new temporary folder of the job's, named in the environment (:data:`_TEMPORARY`),
    where the temporary folder is one of those leading to ``hidden``; else None."""
    if os.path.realpath(tempfile.gettempdir()) not in _leading_folders(hidden):
        return None
    own = tempfile.mkdtemp(prefix="jointbench-job-")
    for name in _TEMPORARY:
        os.environ[name] = own
    return own


def _add_rule(ruleset: int, path: str, rights: int) -> None:
    """Grant ``rights`` on ``path`` and below (a file: its file rights alone), if it exists
    and is its own real path."""
    if os.path.realpath(path) != path:
        return
    try:
        opened = os.open(path, os.O_PATH | os.O_NOFOLLOW | os.O_CLOEXEC)
    except FileNotFoundError:
        return
    try:
        if not stat.S_ISDIR(os.fstat(opened).st_mode):
            rights &= _FILE_RIGHTS
        rule = _PathBeneathAttr(rights, opened)
        _syscall(_ADD_RULE, ruleset, _RULE_PATH_BENEATH, ctypes.byref(rule), 0)
    finally:
        os.close(opened)


def text_from(environ: Mapping[str, str]) -> str:
    """:data:`VARIABLE`'s text in ``environ``; ``ValueError`` when it is not set: a job never
    runs unconfined for want of it."""
    text = environ.get(VARIABLE)
    if text is None:
        raise ValueError(f"{VARIABLE} is not set: the workflow sets it when it loads")
    return text
