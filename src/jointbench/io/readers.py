"""Readers for C3D, TRC and the long CSV ``frame,marker,x,y,z``; all give a :class:`Recording`."""

from __future__ import annotations

import codecs
import csv
import io
import itertools
import math
import re
import struct
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd

from jointbench.io.caller import warn_caller
from jointbench.io.recording import Recording
from jointbench.io.units import UNIT_READ, UNIT_TO_MM, read_unit, to_mm

__all__ = ["UNIT_TO_MM", "read", "read_c3d", "read_csv", "read_trc"]


def _check_file(path: str | Path) -> Path:
    path = Path(path)
    if not path.exists():
        raise ValueError(f"{path}: no such file")
    if not path.is_file():
        raise ValueError(f"{path}: is a directory, not a marker file")
    return path


def _read_text(path: Path, kind: str) -> str:
    """The text of ``path``, a ``kind`` (``"TRC"``, ``"CSV"``) file, decoded as UTF-8 (a
    byte-order mark dropped), its bytes checked by :func:`_text_bytes`."""
    return _text_bytes(path, kind).decode("utf-8-sig")


def _text_bytes(path: Path, kind: str) -> bytes:
    """The bytes of ``path``, a ``kind`` (``"TRC"``, ``"CSV"``) file, checked as UTF-8 text;
    ``ValueError`` naming the line and the byte that is not UTF-8, or a binary file
    (:func:`_check_not_binary`). No other encoding is guessed: a Latin-1 or Windows-1252 label
    read as UTF-8 with replacement characters would be a label nobody can type, and one read
    as Latin-1 from a Windows-1252 file would be another marker's name. The end-of-file mark
    some DOS programs end a file with (0x1a) ends the text: kept, it would read as a last line
    cut short. ASCII text, as most exports are, is UTF-8 as it is: only other text is decoded
    to be checked, a copy of it the size of the file's."""
    content = path.read_bytes().removesuffix(_DOS_END)
    _check_not_binary(content, path, kind)
    if content.isascii():
        return content
    try:
        content.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = content.count(b"\n", 0, error.start) + 1
        raise ValueError(
            f"{path}: line {line}: byte 0x{content[error.start]:02x} (byte {error.start} of the "
            "file) is not UTF-8 text; save the file as UTF-8 (from Latin-1: "
            "iconv -f latin1 -t utf-8)"
        ) from None
    return content


#: The end-of-file mark some DOS programs end a text file with; the text ends before it.
_DOS_END = b"\x1a"

#: What a refusal of a C3D file cut short tells its reader to do: the frames that are there are
#: not the trial, and only a whole copy or a new export from the capture software restores it.
_C3D_CUT_ADVICE = "; copy the file again from where it was recorded, or export it again"

#: Bytes no text file holds: the control characters but tab, line feed, vertical tab, form
#: feed, carriage return and the end-of-file mark (0x1a) some DOS programs end a file with.
_BINARY_BYTE = re.compile(rb"[\x00-\x08\x0e-\x19\x1b-\x1f]")


def _check_not_binary(content: bytes, path: Path, kind: str) -> None:
    """``ValueError`` when ``content``, the bytes of ``path`` read as a ``kind`` text file,
    holds a control character no text holds: a C3D file (its first byte the parameters' block,
    a control character, its second 0x50) under a text extension, named so, or another
    program's binary format, naming the first such byte (0-based). Read as text, such a file
    would be refused as text of another encoding, a remedy no binary file takes. Text that
    ends in zero bytes only was cut short and zero-filled, and is refused as such. Text in
    UTF-16, whose byte-order mark says so, is text, whose zero bytes are left to the UTF-8
    refusal."""
    found = _BINARY_BYTE.search(content)
    if found is None or content.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return
    if not content[found.start() :].strip(b"\x00"):
        line = content.count(b"\n", 0, found.start()) + 1
        raise ValueError(
            f"{path}: the file ends in {len(content) - found.start()} zero bytes, from byte "
            f"{found.start()} (line {line}) on: it was cut short there and filled with zeros, as "
            "a crash or a full disk leaves a file"
        )
    if len(content) > 1 and content[0] < 0x20 and content[1] == 0x50:
        raise ValueError(
            f"{path}: a binary file, not {kind} text: its first bytes are a C3D file's; name it "
            ".c3d"
        )
    raise ValueError(
        f"{path}: a binary file, not {kind} text: byte {found.start()} is "
        f"0x{content[found.start()]:02x}, a control character no text holds (a spreadsheet, or "
        f"another program's own format? export it as {kind})"
    )


def read(path: str | Path) -> Recording:
    """Read a recording by its extension: ``.c3d``, ``.trc`` or ``.csv``."""
    path = _check_file(path)
    readers = {".c3d": read_c3d, ".trc": read_trc, ".csv": read_csv}
    reader = readers.get(path.suffix.lower())
    if reader is None:
        raise ValueError(
            f"{path}: unknown file type {path.suffix!r}; jointbench reads .c3d, .trc and .csv"
        )
    return reader(path)


def read_c3d(path: str | Path) -> Recording:
    """A C3D file via ``ezc3d``: POINT labels, rate and units; negative residuals are gaps.

    The file must hold every frame its header promises (:func:`_check_c3d_size`); row 0 is the
    header's first frame, numbered as in the file (1-based, as other software shows it). A file
    that states no point unit (no ``POINT:UNITS``, or a blank one) is read as mm, with a
    warning, and its recording's ``units`` is ``""``. A point at exactly (0, 0, 0) with no
    negative residual is read by the rule of every format
    (:func:`~jointbench.io.recording.origin_gaps`); frames stored other than the file's
    ``POINT:SCALE`` says are refused (:func:`_c3d_word`).
    """
    path = _check_file(path)
    try:
        c3d = ezc3d.c3d(str(path))
    except Exception as error:  # ezc3d raises bare RuntimeError/IOError for any bad file
        _check_c3d_reaches_frames(path)
        # ezc3d fails on a rate of NaN: the file's own word names it.
        rate = _c3d_float_parameter(path, "POINT", "RATE")
        if rate is not None:
            _c3d_rate(rate, path)
        raise ValueError(f"{path}: not a readable C3D file ({error})") from None
    _check_c3d_size(c3d, path)
    points = c3d["data"]["points"]
    labels = _c3d_labels(c3d["parameters"]["POINT"], points.shape[1], path)
    units = _c3d_units(c3d, path, len(labels))
    markers = np.transpose(points[:3], (2, 1, 0)) * to_mm(read_unit(units), path)
    residuals = c3d["data"]["meta_points"]["residuals"]
    if residuals.size:
        markers[np.transpose(residuals[0]) < 0] = np.nan
    rate = _c3d_rate(float(c3d["header"]["points"]["frame_rate"]), path)
    # ezc3d counts frames from 0; the file (and every other program) from 1.
    first = int(c3d["header"]["points"]["first_frame"]) + 1
    return _no_repeated_frames(Recording(tuple(labels), markers, rate, str(path), first, units))


def _c3d_labels(point: dict, n_points: int, path: Path) -> list[str]:
    """The labels of the ``n_points`` points of the C3D file ``path`` (``point``, its POINT
    group as ezc3d reads it): ``LABELS``, then ``LABELS2`` and ``LABELS3`` where more points
    need them, stripped of spaces; labels past the points are not read. ``ValueError`` naming
    the file where they are fewer than the points (``POINT:USED``), or a point's is empty:
    either would leave a marker's coordinates without a name to take them by (or with
    another's, shifting every label after it), as a TRC's empty label is refused."""
    labels = list(point["LABELS"]["value"])
    for extra in ("LABELS2", "LABELS3"):
        if extra in point:
            labels += list(point[extra]["value"])
    labels = [label.strip() for label in labels[:n_points]]
    if len(labels) < n_points:
        raise ValueError(
            f"{path}: POINT:USED counts {n_points} points, but POINT:LABELS (with LABELS2, "
            f"LABELS3) names {len(labels)}; every point needs a label"
        )
    empty = [i + 1 for i, label in enumerate(labels) if not label]
    if empty:
        raise ValueError(
            f"{path}: POINT:LABELS: point {empty[0]} (of {n_points}) has no label, an empty "
            f"one ({len(empty)} in all); every marker needs a label (relabel those points, or "
            "export the trial without unlabelled trajectories)"
        )
    return labels


def _c3d_units(c3d: ezc3d.c3d, path: Path, n_points: int) -> str:
    """The point unit the C3D file ``path`` of ``n_points`` points states in ``POINT:UNITS``,
    ``""`` where it states none: no such parameter, which ezc3d adds as ``mm`` on reading (so
    the file's own parameters are looked at for an ``mm``), or a blank one. Its coordinates
    are then read as mm, which a warning says, unless it holds no points (an analog-only
    file), whose unit nothing reads. A unit other than ``mm`` is the file's whatever the walk
    of its parameters finds: ezc3d supplies no other."""
    value = c3d["parameters"]["POINT"].get("UNITS", {}).get("value", [])
    stated = str(value[0]).strip() if len(value) else ""
    if stated and (stated != "mm" or _c3d_parameter(path, "POINT", "UNITS") is not None):
        return stated
    if n_points == 0:
        return ""
    warn_caller(
        f"{path}: the file states no point unit (POINT:UNITS); its coordinates are read as "
        f"{UNIT_READ}"
    )
    return ""


def _c3d_rate(rate: float, path: Path) -> float | None:
    """The C3D file ``path``'s point rate ``rate`` [Hz], ``None`` for 0, the rate of a file
    that states none; ``ValueError`` naming ``POINT:RATE`` for a negative or infinite one,
    which no recording has, as a TRC's ``DataRate`` is refused (:func:`_trc_rate`)."""
    if rate == 0:
        return None
    if not (math.isfinite(rate) and rate > 0):
        raise ValueError(f"{path}: POINT:RATE {rate:g} is not a frame rate (frames per second)")
    return rate


def _c3d_float_parameter(path: Path, group: str, name: str) -> float | None:
    """The first value of the C3D file ``path``'s float parameter ``group:name``, read from
    the file itself (:func:`_c3d_parameter`); ``None`` where it has none, or it is no float
    (or a DEC processor's, which this does not decode)."""
    found = _c3d_parameter(path, group, name)
    if found is None or found[0] != 4 or len(found[1]) < 4 or found[2] is None:
        return None
    return struct.unpack(found[2] + "f", found[1][:4])[0]


def _c3d_parameter(path: Path, group: str, name: str) -> tuple[int, bytes, str | None] | None:
    """The C3D file ``path``'s parameter ``group:name`` as its parameter section writes it: its
    type (-1 text, 1 byte, 2 int16, 4 float), its value's bytes and their byte order (``"<"``
    or ``">"``; ``None`` for a DEC processor's floats); ``None`` where the section holds no
    such parameter or cannot be walked. ezc3d adds the parameters a file lacks, and fails on
    some values without naming them, so those questions are put to the file itself.

    The section starts at the 512-byte block the header's first byte names, with 4 bytes (the
    processor's code last: 84 Intel, 85 DEC, 86 MIPS); each entry then writes its name's
    length (negative where locked; 0 ends the section), its group's id (negative for a group
    itself), its name, a 16-bit offset from that word to the next entry (0 for the last), and,
    for a parameter, its type, its number of dimensions, the dimensions (a byte each) and the
    value."""
    try:
        content = _c3d_parameter_section(path)
        processor = content[3]
        order = _c3d_order(processor)
        groups: dict[int, str] = {}
        found: dict[tuple[int, str], tuple[int, bytes]] = {}
        at = 4
        while at < len(content):
            length, number = struct.unpack("bb", content[at : at + 2])
            if length == 0:
                break
            entry = content[at + 2 : at + 2 + abs(length)].decode("ascii", "replace").upper()
            (offset,) = struct.unpack(
                order + "h", content[at + 2 + abs(length) : at + 4 + abs(length)]
            )
            body = at + 4 + abs(length)
            if number < 0:
                groups[-number] = entry
            else:
                kind, n_dims = struct.unpack("bb", content[body : body + 2])
                dims = content[body + 2 : body + 2 + n_dims]
                size = abs(kind) * math.prod(dims)
                value = content[body + 2 + n_dims : body + 2 + n_dims + size]
                found[(number, entry)] = (kind, value)
            if offset <= 0:
                break
            at = body - 2 + offset
    except (IndexError, struct.error):
        return None
    # A group may be written more than once (a program appending a parameter to it), each
    # with an id of its own; ezc3d reads them as one group, and so the parameter is looked
    # for under each.
    ids = [number for number, title in groups.items() if title == group.upper()]
    entries = [found[(number, name.upper())] for number in ids if (number, name.upper()) in found]
    if not entries:
        return None
    kind, value = entries[0]
    return kind, value, None if processor == 85 and kind == 4 else order


def _c3d_parameter_section(path: Path) -> bytes:
    """The bytes of the C3D file ``path``'s parameter section: from the block the header's
    first byte names to the frames' first block, or over the blocks its third byte counts
    where that is more (a writer may leave blocks between them). ``IndexError`` or
    ``struct.error`` for a file too short to hold a header."""
    data_start = (_c3d_header(path)[-1] - 1) * 512
    with path.open("rb") as file:
        start = max(0, (file.read(1)[0] - 1) * 512)
        file.seek(start)
        content = file.read(4)
        blocks = content[2] if len(content) == 4 else 0
        return content + file.read(max(0, max(blocks * 512, data_start - start) - 4))


def _check_c3d_size(c3d: ezc3d.c3d, path: Path) -> None:
    """``ValueError`` when the file ends before the frames its header promises (a last frame of
    65535, the most a header counts, promises at least the frames up to it), or holds more
    than ezc3d reads of a long file (:func:`_check_c3d_long`).

    ezc3d reads the frames that are there and rewrites its header and ``POINT:FRAMES`` to
    match, so the promise is read from the file's own header block: the number of points, of
    analog samples per frame (all channels), the first and last frame and the data's first
    512-byte block. Each frame holds, per point, x, y, z and a residual word, then the analog
    samples, each value a float32 (``POINT:SCALE`` < 0) or an int16.
    """
    n_points, n_analog, first, last, data_block = _c3d_header(path)
    word = _c3d_word(c3d, path)
    start = (data_block - 1) * 512
    frame_bytes = word * (4 * n_points + n_analog)
    size = path.stat().st_size
    # A last frame of 65535, the most the header counts, promises that many or more.
    more = " or more" if last == 0xFFFF else ""
    frames = last - first + 1
    if frames > 0 and size < start + frames * frame_bytes:
        complete = max(0, (size - start) // frame_bytes)
        raise ValueError(
            f"{path}: truncated C3D file: its header promises frames {first} to {last}{more} "
            f"({frames} frames{more}) of {n_points} points and {n_analog} analog samples each "
            f"({start + frames * frame_bytes} bytes{more}), but the file has {size} bytes: "
            f"{complete} complete frames{_C3D_CUT_ADVICE}"
            f"{_c3d_integers_advice(c3d, path, start + frames * frame_bytes // 2, word)}"
        )
    if more:
        _check_c3d_long(c3d, path, start, frame_bytes, first)


def _c3d_integers_advice(c3d: ezc3d.c3d, path: Path, end: int, word: int) -> str:
    """For the refusal of the C3D file ``path`` as too short for its frames of floats (``word``
    4), what else it may be where it ends where its frames as 16-bit integers end (byte
    ``end``) or at the end of that 512-byte block: frames of integers under a negative
    ``POINT:SCALE``, which a copy does not mend; ``""`` otherwise."""
    if word != 4 or path.stat().st_size not in (end, -(-end // 512) * 512):
        return ""
    return (
        "; or, as the file ends where its frames end as 16-bit integers (or at the end of that "
        "512-byte block), they are integers under a POINT:SCALE of "
        f"{_c3d_scale(c3d, path):.3g} that says floats: export the trial again (its "
        "POINT:SCALE positive, for integers)"
    )


def _c3d_word(c3d: ezc3d.c3d, path: Path) -> int:
    """The bytes of each value in the frames of the C3D file ``path``: 4 for floats, 2 for
    16-bit integers, as the sign of its ``POINT:SCALE`` says (:func:`_c3d_scale`): "a negative
    SCALE factor indicates that the C3D file contains 3D points that have been pre-scaled and
    stored as floating-point values" (c3d.org, POINT:SCALE). ``ValueError`` naming both where
    its header's copy of the scale (words 7-8) has the other sign: a file that disagrees with
    itself, which ezc3d reads without a word as integers in all or some of its frames. And
    so where the scale is positive but the frames take a float's 4 bytes a value (the bytes
    past the integers' share not all zero): ezc3d reads them as integers, every coordinate
    another number. Not so in a file whose header's last frame is 65535, the most it counts:
    the bytes past its integers' share may be its frames past those, which
    :func:`_check_c3d_long` refuses."""
    scale = _c3d_scale(c3d, path)
    header = _c3d_header_scale(path)
    agree = header is None or (header < 0) == (scale < 0)
    n_points, n_analog, first, last, data_block = _c3d_header(path)
    start = (data_block - 1) * 512
    frames = max(0, last - first + 1)
    int_bytes = 2 * (4 * n_points + n_analog) * frames
    size = path.stat().st_size
    holds_floats = n_points > 0 and last != 0xFFFF and size >= start + 2 * int_bytes
    if agree and scale < 0:
        return 4
    if agree and holds_floats:
        with path.open("rb") as file:
            file.seek(start + int_bytes)
            holds_floats = file.read(int_bytes).strip(b"\x00") != b""
    if agree and not holds_floats:
        return 2
    floats = (
        f"the file's {size} bytes hold its {frames} frames of its {n_points} points' "
        f"coordinates as {_C3D_STORAGE[True]}"
    )
    if agree:
        raise ValueError(
            f"{path}: POINT:SCALE {scale:.3g} and its header's scale say its coordinates are "
            f"{_C3D_STORAGE[False]} (a positive scale), but {floats}, as a negative scale says: "
            "read as integers, every coordinate would be another number; export the trial "
            "again (its POINT:SCALE negative, for floats)"
        )
    says = (
        f"{path}: POINT:SCALE {scale:.3g} says its coordinates are {_C3D_STORAGE[scale < 0]} "
        f"(a {_SIGN[scale < 0]} scale), its header's scale {header:.3g} says "
        f"{_C3D_STORAGE[header < 0]} (a {_SIGN[header < 0]} one): a file that disagrees with "
        "itself, which ezc3d reads as integers in all or some of its frames"
    )
    if holds_floats:
        raise ValueError(
            f"{says}; {floats}, and those read as integers would be other numbers; export the "
            "trial again (both scales negative, for floats)"
        )
    raise ValueError(f"{says}; export the trial again (both scales of one sign)")


#: How a C3D's frames store each value, by whether its scale is negative.
_C3D_STORAGE = {True: "32-bit floats", False: "16-bit integers"}
_SIGN = {True: "negative", False: "positive"}


def _c3d_header_scale(path: Path) -> float | None:
    """The scale the C3D file ``path``'s header block copies from ``POINT:SCALE`` (words 7-8),
    ``None`` where it is 0 or not finite (a writer that leaves it unset) or a DEC processor's
    float, which this does not decode."""
    block, processor = _c3d_header_block(path)
    if processor == 85 or len(block) < 16:
        return None
    (scale,) = struct.unpack(_c3d_order(processor) + "f", block[12:16])
    return scale if math.isfinite(scale) and scale != 0 else None


def _c3d_scale(c3d: ezc3d.c3d, path: Path) -> float:
    """The C3D file ``path``'s ``POINT:SCALE`` (-1, a float file's, where it has none);
    ``ValueError`` naming it where it is 0 or not finite, which makes no format: its sign
    says whether the coordinates are floats (negative) or integers (positive, their step in
    the file's unit), and 0 or NaN would make every coordinate 0 or NaN, every sample a gap."""
    value = c3d["parameters"]["POINT"].get("SCALE", {"value": [-1.0]})["value"]
    scale = float(value[0]) if len(value) else -1.0
    if scale == 0 or not math.isfinite(scale):
        raise ValueError(
            f"{path}: POINT:SCALE {scale:g} is no scale: a float file's is negative, an integer "
            "file's the size of its unit step (0 or NaN would make every coordinate 0 or NaN, "
            "and so every sample a gap)"
        )
    return scale


def _check_c3d_long(c3d: ezc3d.c3d, path: Path, start: int, frame_bytes: int, first: int) -> None:
    """``ValueError`` when the C3D file ``path``, whose header's last frame is 65535, the most
    it can count, holds frames past those ezc3d read (``c3d``), which would be left out unseen:
    ezc3d reads the frames its header and ``POINT:FRAMES`` count, not those a file's
    ``POINT:LONG_FRAMES`` or ``TRIAL`` group count past them (nor those of a file, such as
    ezc3d itself writes, whose parameters count no more). Its frames start at byte ``start``,
    take ``frame_bytes`` each and are numbered from ``first``; up to a 512-byte block of
    padding may follow them (ezc3d writes a whole one where they end a block), so the frames
    past them are counted within that. Padding is zero bytes: a frame smaller than a block
    may end the block the last frame read ends in (frame 65536 always ends a block), and
    bytes there that are not zero are such frames, not padding."""
    header = c3d["header"]["points"]
    read = int(header["last_frame"]) - int(header["first_frame"]) + 1
    end = start + read * frame_bytes
    extra = path.stat().st_size - end
    if frame_bytes == 0 or extra < frame_bytes:
        return
    with path.open("rb") as file:
        file.seek(end)
        written = file.read().rstrip(b"\x00")
    if extra <= 512 and not written:
        return
    fewest = max(-(-(extra - 512) // frame_bytes), -(-len(written) // frame_bytes))
    most = extra // frame_bytes
    more = f"{fewest}" if fewest == most else f"{fewest} to {most}"
    n_points, n_analog = _c3d_header(path)[:2]
    raise ValueError(
        f"{path}: the file holds {extra} bytes past the {read} frames read, room for {more} "
        f"more frames of {n_points} points and {n_analog} analog samples each (a C3D's header "
        "counts at most 65535 frames, and frames past those its header and POINT:FRAMES count "
        "are not read, whatever its POINT:LONG_FRAMES or TRIAL:ACTUAL_END_FIELD say): frames "
        f"from {first + read} on would be left out unread; export the trial as TRC, or in parts"
    )


def _c3d_header(path: Path) -> tuple[int, int, int, int, int]:
    """The words of a C3D file's header block that say how long it is: the number of points,
    of analog samples per frame, the first and last frame, and the 512-byte block (1-based)
    where the frames start. The byte order is the parameter section's processor's; a file cut
    before it is read as Intel's, the commonest."""
    block, processor = _c3d_header_block(path)
    order = _c3d_order(processor)
    n_points, n_analog, first, last = struct.unpack(order + "4H", block[2:10])
    (data_block,) = struct.unpack(order + "H", block[16:18])
    return n_points, n_analog, first, last, data_block


def _c3d_header_block(path: Path) -> tuple[bytes, int | None]:
    """The C3D file ``path``'s 512-byte header block and its processor's code (84 Intel, 85
    DEC, 86 MIPS), the 4th byte of the parameter section the header's first byte places;
    ``None`` where the file ends before it."""
    with path.open("rb") as file:
        block = file.read(512)
        file.seek(max(0, (block[0] - 1) * 512 + 3))
        processor = file.read(1)
    return block, processor[0] if processor else None


def _c3d_order(processor: int | None) -> str:
    """The byte order (``struct``'s ``"<"`` or ``">"``) of a C3D processor's integers: Intel
    (84) and DEC (85) store them little-endian, MIPS (86) big-endian; a file cut before its
    processor's code is read as Intel's, the commonest."""
    return ">" if processor == 86 else "<"


def _check_c3d_reaches_frames(path: Path) -> None:
    """``ValueError`` when ``path``, a file ezc3d cannot read, ends before the frames its
    header block places (or inside that block): a file cut short, which ezc3d reports as
    malformed parameters or a bad processor type. A file whose second byte is not the 0x50
    every C3D header starts with is no C3D file, cut or not, and is left to ezc3d's message."""
    with path.open("rb") as file:
        key = file.read(2)[1:]
    if key != b"\x50":
        return
    size = path.stat().st_size
    if size < 512:
        raise ValueError(
            f"{path}: truncated C3D file: it ends after {size} bytes, inside its 512-byte "
            f"header block{_C3D_CUT_ADVICE}"
        )
    start = (_c3d_header(path)[-1] - 1) * 512
    if size < start:
        raise ValueError(
            f"{path}: truncated C3D file: it ends after {size} bytes, inside its parameters, "
            f"before the frames its header places at byte {start}{_C3D_CUT_ADVICE}"
        )


def read_trc(path: str | Path) -> Recording:
    """A TRC file (OpenSim / Motion Analysis): header keys ``DataRate``, ``Units``,
    ``NumFrames``, ``NumMarkers``, then ``Frame#  Time  label  …`` with one ``X Y Z`` triple per
    label; empty fields are gaps. The rows must be the ``NumFrames`` consecutive frames the
    header promises, each with every field of the header (a line cut short is refused, naming
    it, and so is a last line the file ends inside with its last field empty where other rows
    fill it: cut right after a separator), and so is a frame on line 5, where the ``X1 Y1 Z1``
    names belong (:func:`_check_names_line`); row 0 is the first row's ``Frame#``. Labels sit at
    fixed columns (:func:`_trc_labels`) and no row may write past the labelled markers
    (:func:`_check_unlabelled_fields`); the file is UTF-8 (:func:`_read_text`). Its fields are
    tab-separated: a line of fields separated by spaces is refused, naming it, not read
    (:func:`_check_tab_separated`), and so is an empty ``Units``: a TRC states its unit. The
    rows are read line by line into one array (:func:`_trc_rows`): a long capture is read in
    about twice its file's size (its text and its numbers), not its fields as text, ten times."""
    path = _check_file(path)
    text = _read_text(path, "TRC")
    n_lines = sum(1 for _ in _text_lines(text))
    if n_lines < 6:
        raise ValueError(f"{path}: too short for a TRC file (needs 5 header lines and data)")
    head = list(itertools.islice(_text_lines(text), 5))
    # The header's keys, their values and the labels (lines 2 to 4): read split at tabs, a
    # line of spaces would be refused as lacking what it holds.
    for index in (1, 2, 3):
        _check_tab_separated(head[index], index + 1, path)
    keys, values = head[1].split("\t"), head[2].split("\t")
    header = {key.strip(): value.strip() for key, value in zip(keys, values, strict=False)}
    if "Units" not in header:
        raise ValueError(f"{path}: TRC header has no 'Units' (line 2 keys: {keys})")
    if not header["Units"]:
        raise ValueError(
            f"{path}: line 3, field Units: empty; a TRC file states its point unit there (mm, "
            "cm or m)"
        )
    labels = _trc_labels(head[3], path)
    width = 2 + 3 * len(labels)
    # The rows are read twice, line by line, never all split at once: a long capture's fields
    # as text take ten times the file's size. First their count and their fields' (a line cut
    # short is refused before any is read as numbers), then their values.
    n_rows, last_row = 0, 0
    for number, line in _trc_data(text):
        fields = line.count("\t") + 1
        if fields == 1:
            _check_tab_separated(line, number, path)
        if fields < width:
            columns = f"Frame#, Time and X, Y, Z of {len(labels)} markers"
            raise _short_row(path, number, fields, width, columns, number == n_lines)
        n_rows, last_row = n_rows + 1, number
    if not n_rows:
        raise ValueError(f"{path}: no frames: the TRC header is followed by blank lines only")
    _check_names_line(head[4].split("\t"), path)
    _check_unlabelled_fields(head[4].split("\t"), width, path, 5)
    # The last field of every row, for a file that ends inside its last line.
    cut = last_row == n_lines and not _ends_with_newline(path)
    rows = _trc_rows(text, n_rows, width, path, cut)
    del text  # the values are read: the file's text is no longer needed
    if cut:
        _check_last_field(path, n_lines, rows.last_field, f"Z of {labels[-1]}")
    numbers = _trc_frame_numbers(rows.frames, rows.lines, header, len(labels), path)
    if rows.not_a_number is not None:
        i, j, text = rows.not_a_number
        raise ValueError(
            f"{path}: frame {numbers[i]}, marker {labels[j // 3]}: {text!r} is not a number"
            f"{_decimal_comma(text)}"
        )
    markers = rows.values.reshape(n_rows, len(labels), 3)
    markers *= to_mm(header["Units"], path)
    rate_hz = _trc_rate(header.get("DataRate", ""), path)
    _check_trc_times(rows.times, rows.lines, numbers, rate_hz, path)
    return _no_repeated_frames(
        Recording(tuple(labels), markers, rate_hz, str(path), numbers[0], header["Units"])
    )


def _text_lines(text: str) -> Iterator[str]:
    """The lines of ``text``, as :meth:`str.splitlines` gives them, a part of the text of about
    :data:`_PART_CHARACTERS` at a time: a long file's lines are never all held at once. Each part
    ends with a line feed, so a line (and a ``\\r\\n``) is never split between two."""
    start = 0
    while start < len(text):
        end = text.find("\n", start + _PART_CHARACTERS)
        end = len(text) if end < 0 else end + 1
        yield from text[start:end].splitlines()
        start = end


#: The characters of text split into lines at once (:func:`_text_lines`).
_PART_CHARACTERS = 1 << 18


def _trc_data(text: str) -> Iterator[tuple[int, str]]:
    """The data lines of the TRC file's ``text``, from line 6, with their 1-based numbers; a
    blank line is no frame."""
    lines = enumerate(_text_lines(text), 1)
    for number, line in lines:
        if number > 5 and line.strip():
            yield number, line


@dataclass
class _TrcRows:
    """The ``n_rows`` data rows of a TRC file as read (:func:`_trc_rows`): ``values``
    ``(n_rows, 3 * n_markers)`` float64, NaN where a field is empty, in the file's unit;
    ``frames`` and ``times`` each row's ``Frame#`` and ``Time`` text, ``lines`` its 1-based
    line; ``last_field`` each row's last field's text where it was asked for (else empty); and
    the first field that is not a number, ``(row, column among the values, text)``, or ``None``."""

    values: np.ndarray
    frames: list[str]
    times: list[str]
    lines: list[int]
    last_field: list[str]
    not_a_number: tuple[int, int, str] | None


def _trc_rows(text: str, n_rows: int, width: int, path: Path, last_field: bool) -> _TrcRows:
    """The ``n_rows`` data rows of the TRC file ``path``, whose ``text`` has rows of ``width``
    fields or more (``Frame#``, ``Time``, X, Y, Z of each labelled marker), read line by line
    into one array, with each row's ``last_field`` where asked; ``ValueError`` naming the first
    line that writes past the labelled markers (:func:`_check_unlabelled_fields`). A field that
    is not a number is refused by the caller, after the frame numbers that name it."""
    values = np.full((n_rows, width - 2), np.nan)
    frames, times, lines, last = [], [], [], []
    not_a_number = None
    for i, (number, line) in enumerate(_trc_data(text)):
        row = line.split("\t")
        _check_unlabelled_fields(row, width, path, number)
        frames.append(row[0])
        times.append(row[1])
        lines.append(number)
        if last_field:
            last.append(row[width - 1])
        if not_a_number is None:
            not_a_number = _read_values(row[2:width], values[i], i)
    return _TrcRows(values, frames, times, lines, last, not_a_number)


def _read_values(fields: list[str], into: np.ndarray, row: int) -> tuple[int, int, str] | None:
    """The numbers ``fields`` write, read into ``into`` ``(len(fields),)``, an empty field left
    as it is (NaN, a gap); the first that is not a number, ``(row, its index, its text)``, or
    ``None``."""
    try:
        into[:] = [float(text) for text in fields]
        return None
    except ValueError:
        pass  # an empty field, or no number: each field read on its own
    for j, text in enumerate(fields):
        text = text.strip()
        if text:
            try:
                into[j] = float(text)
            except ValueError:
                return row, j, text
    return None


def _check_tab_separated(line: str, number: int, path: Path) -> None:
    """``ValueError`` naming line ``number`` (1-based) of the TRC file ``path``, ``line``, when
    it holds no tab but several fields separated by spaces, as an editor or exporter that turns
    tabs into spaces writes. Such a file is refused, not read: spaces cannot tell an empty
    field (a gap) from no field, nor a label with a space in it from two labels."""
    if "\t" in line or len(line.split()) < 2:
        return
    raise ValueError(
        f"{path}: line {number} is not tab-separated: a TRC file's fields are separated by "
        "tabs, and spaces cannot tell an empty field (a gap) from none, nor a label with a "
        "space in it; save the file with tabs"
    )


def _check_trc_times(
    times: list[str], lines: list[int], numbers: list[int], rate: float | None, path: Path
) -> None:
    """``ValueError`` naming the line of the first row of the TRC file ``path`` whose ``Time``
    (``times``, each row's text; ``lines`` their 1-based lines, ``numbers`` their ``Frame#``)
    is not where its frame falls at the header's ``DataRate`` ``rate`` [Hz], counted from the
    first row that writes a time: by more than half a frame, beyond the rounding of the two
    times as written. Recordings of different rates joined, or a wrong ``DataRate``, would
    otherwise read as frames at one rate. Without a rate, and in a row whose time is empty or
    no number, there is nothing to compare; nor in a column that writes one time in every row
    (left unfilled by its writer: all zeros), which states no rate."""
    if rate is None:
        return
    seconds = pd.to_numeric(pd.Series(times, dtype=object), errors="coerce").to_numpy(float)
    timed = np.flatnonzero(np.isfinite(seconds))
    if timed.size == 0 or np.all(seconds[timed] == seconds[timed[0]]):
        return
    first = int(timed[0])
    expected = seconds[first] + (np.asarray(numbers) - numbers[first]) / rate
    # Only rows off by over half a frame can be off beyond their rounding: the rest pass
    # unread, so that a long file's rows are not each read again as text.
    for i in np.flatnonzero(np.abs(seconds - expected) > 0.5 / rate):
        text, first_text = times[i].strip(), times[first].strip()
        if abs(seconds[i] - expected[i]) > 0.5 / rate + _rounding(first_text) + _rounding(text):
            raise ValueError(
                f"{path}: line {lines[i]}, field Time: {text} s, where frame {numbers[i]} falls "
                f"at {expected[i]:.6g} s at the header's DataRate of {rate:g} Hz (frame "
                f"{numbers[first]} at {first_text} s, line {lines[first]}): the frames are not "
                "at that rate; a wrong DataRate, or recordings of different rates joined?"
            )


def _rounding(text: str) -> float:
    """Half the last written digit's unit of the number ``text`` (``0.0005`` for
    ``"0.125"``): how far rounding may have put it from its value; 0 for an exponent form,
    whose digits are taken as exact."""
    decimals = _decimals(text)
    return 0.0 if decimals is None else 0.5 * 10.0**-decimals


def _trc_labels(line: str, path: Path) -> list[str]:
    """The marker labels of a TRC file's line 4, ``Frame#  Time  label  …`` (tab-separated).

    Marker ``k`` (0-based) owns columns ``3 + 3k`` to ``5 + 3k`` (1-based), its label in the
    first; empty cells after the last label are allowed. ``ValueError`` naming the column for
    a label off that boundary, or for an empty cell where a marker's label must be: either
    would pair the labels that follow with another marker's coordinates."""
    names = [name.strip() for name in line.split("\t")[2:]]
    for i, name in enumerate(names):
        if name and i % 3:
            raise ValueError(
                f"{path}: line 4, column {i + 3}: label {name!r} is not at a marker's first "
                "column; a TRC file's labels sit at columns 3, 6, 9, ... (one per X, Y, Z)"
            )
    named = [i for i, name in enumerate(names) if name]
    if not named:
        raise ValueError(f"{path}: line 4 names no marker (labels from column 3 on)")
    labels = names[: named[-1] + 1 : 3]
    for k, label in enumerate(labels):
        if not label:
            raise ValueError(
                f"{path}: line 4, column {3 * k + 3}: marker {k + 1} has no label (an empty "
                "cell where its label must be); every marker's X, Y, Z must be named"
            )
    return labels


def _check_names_line(row: list[str], path: Path) -> None:
    """``ValueError`` when line 5 of the TRC file ``path`` (its tab-separated fields ``row``),
    where each marker's ``X1 Y1 Z1`` are named, holds a frame instead: a file written without
    that line, whose first frame would be read as the names and lost."""
    number = _whole_number(row[0])
    if number is None:
        return
    raise ValueError(
        f"{path}: line 5 holds frame {number}, where a TRC file names each marker's X, Y and Z "
        "(its Frame# and Time fields empty); read as those names, the frame would be lost"
    )


def _check_unlabelled_fields(row: list[str], width: int, path: Path, line: int) -> None:
    """``ValueError`` naming line ``line`` (1-based) of ``path`` and the column when ``row``
    (its tab-separated fields) writes anything past the ``width`` columns that ``Frame#``,
    ``Time`` and the labelled markers' X, Y, Z explain: a marker without a label, whose data
    would otherwise be cut off unseen. Empty fields past them are allowed."""
    extra = [i for i, text in enumerate(row[width:], width) if text.strip()]
    if extra:
        column = extra[0] + 1
        raise ValueError(
            f"{path}: line {line}, column {column}: {row[extra[0]].strip()!r} belongs to marker "
            f"{(column - 3) // 3 + 1}, but line 4 labels {(width - 2) // 3} markers "
            f"(columns 1 to {width}); label every marker, or remove its columns"
        )


def _decimal_comma(text: str) -> str:
    """For the refusal of ``text`` as a number, what it reads as with its comma a decimal point
    (``" (a decimal comma? write 0.5)"``), or ``""``."""
    if "," not in text:
        return ""
    try:
        float(text.strip().replace(",", "."))
    except ValueError:
        return ""
    return f" (a decimal comma? write {text.strip().replace(',', '.')})"


def _trc_rate(text: str, path: Path) -> float | None:
    """The header's ``DataRate`` [Hz], ``None`` when it is empty or absent; ``ValueError``
    naming line 3 when it is not a positive finite number."""
    if not text:
        return None
    try:
        rate = float(text)
    except ValueError:
        rate = math.nan
    if not (math.isfinite(rate) and rate > 0):
        raise ValueError(
            f"{path}: line 3, field DataRate: {text!r} is not a frame rate (frames per second)"
        )
    return rate


def _short_row(
    path: Path, line: int, found: int, expected: int, columns: str, last: bool
) -> ValueError:
    """The refusal of line ``line`` (1-based) of ``path``, which has ``found`` fields where its
    header has ``expected`` (``columns``); ``last`` when it is the file's last line. A gap is
    an empty field between separators: a row missing fields is a line cut short or written
    wrong, and reading it as a gap would hide that."""
    cut = last and not _ends_with_newline(path)
    return ValueError(
        f"{path}: line {line} has {found} fields, but the header has {expected} ({columns})"
        + ("; the file ends inside this line: it was cut short" if cut else "")
        + "; a gap is an empty field, not a missing one"
    )


def _check_last_field(path: Path, line: int, column: list[str], name: str) -> None:
    """``ValueError`` when ``path`` ends inside its last line, ``line`` (1-based), and the
    line's last field (``name``; ``column``, its text in every row) shows the cut: empty
    (:func:`_check_cut_after_separator`) or a number shorter than the others
    (:func:`_check_cut_inside_number`)."""
    _check_cut_after_separator(path, line, column, name)
    _check_cut_inside_number(path, line, column, name)


def _check_cut_inside_number(path: Path, line: int, column: list[str], name: str) -> None:
    """``ValueError`` when ``path`` ends inside its last line, ``line`` (1-based; no newline
    follows it), and that line's last field (``name``) has fewer decimals than every other row
    writes in it: the file was cut inside the number, which reads as another value (``12.3``
    of ``12.345``). ``column``: that field's text in every row, the last line's last. A writer
    whose decimals vary from row to row, or that writes exponents, leaves nothing to tell a cut
    by, and the field is read as it is."""
    *others, last = (text.strip() for text in column)
    written = {_decimals(text) for text in others if text}
    found = _decimals(last)
    if len(written) != 1 or None in written or found is None or _ends_with_newline(path):
        return
    (decimals,) = written
    if found >= decimals:
        return
    raise ValueError(
        f"{path}: line {line} ends its last field ({name}) with {last!r}, {found} decimals where "
        f"every other row writes {decimals}, and the file ends inside this line: it was cut "
        "short inside a number; if the value is whole, end the line with a newline"
    )


def _decimals(text: str) -> int | None:
    """The digits written after the decimal point of the number ``text``; ``None`` for an
    empty field, an exponent form or no number."""
    if not text or "e" in text.lower():
        return None
    try:
        float(text)
    except ValueError:
        return None
    _, point, fraction = text.partition(".")
    return len(fraction) if point else 0


def _check_cut_after_separator(path: Path, line: int, column: list[str], name: str) -> None:
    """``ValueError`` when ``path`` ends inside its last line, ``line`` (1-based; no newline
    follows it), and that line leaves its last field (``name``) empty where another row has a
    value: the file was cut right after a separator, and reading the field as a gap would hide
    that. ``column``: that field's text in every row, the last line's last."""
    *others, last = column
    if last.strip() or not any(text.strip() for text in others) or _ends_with_newline(path):
        return
    raise ValueError(
        f"{path}: line {line} leaves its last field ({name}) empty, which other rows fill, and "
        "the file ends inside this line, right after a separator: it was cut short; if the "
        "field is a gap, end the line with a newline"
    )


def _ends_with_newline(path: Path) -> bool:
    """Whether the file's text (:func:`_read_text`) ends a line with its last byte (``\\n``,
    or ``\\r`` of an old Mac file)."""
    with path.open("rb") as file:
        file.seek(max(0, path.stat().st_size - 2))
        return file.read().removesuffix(_DOS_END)[-1:] in (b"\n", b"\r")


def _whole_number(text: str) -> int | None:
    """The frame number ``text`` writes in ASCII digits (``7``, or ``7.0`` as some writers give
    one, spaces around it ignored), or None. What Python's ``float`` reads besides is refused: a
    sign (no frame is numbered below 0), an exponent, an underscore, a digit of another script
    (``"\u0661"`` reads as 1), and ``1.5``, whose truncation to 1 would read a file whose frames
    are not what it says as if they were."""
    match = _FRAME_NUMBER.fullmatch(text.strip(" "))
    return int(match.group(1)) if match else None


#: A frame number: ASCII digits, optionally a point and zeros.
_FRAME_NUMBER = re.compile(r"([0-9]+)(?:\.0*)?", re.ASCII)


def _not_a_frame_number(path: Path, where: str, field: str, text: str) -> ValueError:
    """The refusal of ``text``, written in field ``field`` at ``where`` (``"line 7"``) of
    ``path``, which :func:`_whole_number` does not read as a frame number."""
    return ValueError(
        f"{path}: {where}, field {field}: {text!r} is not a frame number (a whole number >= 0 "
        "in ASCII digits)"
    )


def _trc_frame_numbers(
    frames: list[str], lines: list[int], header: dict, n_labels: int, path: Path
) -> list:
    """The frame numbers of every row, ``frames`` its ``Frame#`` text (``lines``: each row's
    1-based line in the file);
    ``ValueError`` when they are not consecutive integers, naming the line of the first one
    that is not (and of the row before it, blank lines between them being no rows), or not the
    frames and markers the header promises."""
    promised = {key: header.get(key, "") for key in ("NumFrames", "NumMarkers")}
    for key, found in (("NumFrames", len(frames)), ("NumMarkers", n_labels)):
        if re.fullmatch(r"[0-9]+", promised[key]) and int(promised[key]) != found:
            raise ValueError(
                f"{path}: the TRC header promises {key} {promised[key]} but the file has {found}"
            )
    numbers = []
    for i, text in enumerate(frames):
        number = _whole_number(text)
        if number is None:
            raise _not_a_frame_number(path, f"line {lines[i]}", "Frame#", text)
        numbers.append(number)
        if i and numbers[i] != numbers[i - 1] + 1:
            raise ValueError(
                f"{path}: line {lines[i]}, field Frame#: frame {numbers[i]} follows frame "
                f"{numbers[i - 1]} (line {lines[i - 1]}); a TRC file's frames must be consecutive"
            )
    return numbers


def read_csv(path: str | Path) -> Recording:
    """The long CSV ``frame,marker,x,y,z`` [mm], one row per sample, rows in any order.

    ``frame`` holds frame numbers as a TRC's ``Frame#`` does (:func:`_whole_number`: ASCII
    digits, ``7.0`` read as 7, no sign or exponent; another is refused, naming its line); row 0
    of the recording is the smallest. A sample absent from the file is a gap, and so is a frame
    absent for every marker (it stays a frame of missing samples, so the frames keep their
    numbers and spacing); a (frame, marker) pair given twice (``7`` and ``7.0`` are one frame)
    is an error. An empty field is a gap too; a row with fewer fields than the
    header (a line cut short) is refused, naming it, and so is a last line the file ends inside
    with its last field empty where other rows fill it (cut right after a separator). The file
    declares no frame count, so a file cut at a line's end reads as a shorter recording.
    ``marker`` is text exactly as written (``01``, ``NA``); an empty one is refused, naming
    its line. The file is UTF-8 (:func:`_text_bytes`).
    """
    path = _check_file(path)
    # The parser reads the file's bytes: its text as a str, copied for the parser at four
    # bytes a character, took five times the file's size.
    content = _text_bytes(path, "CSV")
    _check_not_nexus(content.split(b"\n", 1)[0].decode("utf-8-sig"), path)
    try:
        # The marker column is text as written: no type inference ("01" stays "01") and no
        # missing-value words ("NA" is a marker's name); the other columns keep pandas' own.
        # The frame column is text too, for the frame-number rule: pandas reads "+7", "7e0"
        # and "7_0" as 7, and "-0" as 0. Rows longer than the header would otherwise have
        # their first fields taken for an index, shifting every column; without one, pandas
        # drops the fields past the header and warns (of empty ones too), and those that are not
        # empty are named.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", pd.errors.ParserWarning)
            table = pd.read_csv(
                io.BytesIO(content),
                encoding="utf-8-sig",
                dtype={"marker": str, "frame": str},
                keep_default_na=False,
                na_values={column: _NA_TEXT for column in ("frame", "x", "y", "z")},
                index_col=False,
            )
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as error:
        # pandas ends some of its messages with a newline; the refusal is one line.
        raise ValueError(f"{path}: not a readable CSV file ({str(error).strip()})") from None
    for warning in caught:
        if issubclass(warning.category, pd.errors.ParserWarning):
            _check_csv_extra_fields(path, list(table.columns))  # an empty field loses nothing
        else:
            warn_caller(str(warning.message), warning.category)
    missing = {"frame", "marker", "x", "y", "z"} - set(table.columns)
    if missing:
        # The names as written: a space or another separator is what tells them apart.
        raise ValueError(
            f"{path}: missing columns {sorted(missing)}; the header names {list(table.columns)}; "
            "jointbench reads one row per frame and marker: frame, marker, x, y, z [mm]"
        )
    if table.empty:
        raise ValueError(f"{path}: no samples: the file has a header but no data rows")
    # pandas reads the fields a row lacks as empty, and so as gaps, and so is a line cut right
    # after its last separator; either leaves the last column empty. A cut inside the last
    # number leaves no line end. Only then is the file read again to find it.
    if table[table.columns[-1]].isna().any() or not _ends_with_newline(path):
        _check_csv_fields(path, content, list(table.columns))
    del content  # read: the table holds what the rest of the reading needs
    numbers = _csv_frame_numbers(table["frame"], path)
    table["frame"] = numbers  # "7" and "7.0" are one frame
    empty = (table["marker"] == "").to_numpy()
    if empty.any():
        line, _ = _csv_line(path, int(np.argmax(empty)), "marker")
        raise ValueError(f"{path}: {line}, field marker: empty; every sample needs a marker")
    # Each row's marker as its column, by the labels' natural order: an array of integers, where
    # a mapping of the text column would take ten times the file's size.
    codes, names = pd.factorize(table["marker"])
    order = sorted(range(len(names)), key=lambda code: _natural(names[code]))
    labels = [names[code] for code in order]
    column = np.empty(len(order), dtype=np.intp)
    column[order] = np.arange(len(order))
    column = column[codes]
    first_frame = int(numbers.min())
    markers = np.full((int(numbers.max()) - first_frame + 1, len(labels), 3), np.nan)
    # A sample given twice leaves fewer samples given than rows.
    given = np.zeros(markers.shape[:2], dtype=bool)
    given[numbers - first_frame, column] = True
    if np.count_nonzero(given) < len(column):
        _refuse_csv_repeats(table, numbers, path)
    written = table[["x", "y", "z"]]
    if (written.dtypes == np.float64).all():
        coordinates = written  # numbers as parsed: none to refuse
    else:
        coordinates = written.apply(pd.to_numeric, errors="coerce")
        bad = coordinates.isna().to_numpy() & written.notna().to_numpy()
        if bad.any():
            row, axis = np.argwhere(bad)[0]
            text = written.iloc[row, axis]
            raise ValueError(
                f"{path}: frame {numbers[row]}, marker {table['marker'].iloc[row]}: "
                f"{'xyz'[axis]} = {text!r} is not a number{_decimal_comma(str(text))}"
            )
    markers[numbers - first_frame, column] = coordinates.to_numpy(float)
    del table, written, coordinates  # in the markers now, which the recording copies
    # The format states no unit: its coordinates are read as mm, and said to be read so.
    return _no_repeated_frames(
        Recording(tuple(labels), markers, None, str(path), first_frame, units="")
    )


def _refuse_csv_repeats(table: pd.DataFrame, numbers: np.ndarray, path: Path) -> None:
    """``ValueError`` naming the first (frame, marker) of the CSV file ``path`` (``table``, its
    rows; ``numbers``, their frame numbers) given in more than one row, how many rows give it
    and how many rows in all repeat a sample."""
    twice = table.duplicated(["frame", "marker"], keep=False)
    first = table[twice].iloc[0]
    same = (numbers == numbers[first.name]) & (table["marker"] == first["marker"]).to_numpy()
    raise ValueError(
        f"{path}: frame {numbers[first.name]}, marker {first['marker']} has "
        f"{int(same.sum())} rows for the same (frame, marker); each sample must appear once"
        f" ({int(twice.sum())} rows in all repeat a sample)"
    )


#: The first lines of the sections of a Vicon Nexus CSV export.
_NEXUS_SECTIONS = ("Trajectories", "Devices", "Joints", "Segments", "Model Outputs")


def _check_not_nexus(text: str, path: Path) -> None:
    """``ValueError`` when ``text``, the CSV file ``path``, is a Vicon Nexus export: its first
    line a section's name (:data:`_NEXUS_SECTIONS`), then the rate, the labels and one row per
    frame of three columns per marker, which pandas refuses as rows of more fields than the
    first line's, naming neither the layout nor a remedy."""
    first = text.split("\n", 1)[0].strip().strip(",").strip()
    if first not in _NEXUS_SECTIONS:
        return
    raise ValueError(
        f"{path}: line 1, {first!r}: a Vicon Nexus CSV export (sections of one row per frame, "
        "three columns per marker), not the CSV jointbench reads (one row per frame and marker:"
        " frame, marker, x, y, z); export the trial as C3D or TRC"
    )


def _no_repeated_frames(recording: Recording) -> Recording:
    """``recording``; ``ValueError`` naming the file and the first frame that repeats the frame
    before it to the last bit in every marker, three or more of them seen. Measured positions
    carry noise, so such a frame was written twice (a recording upsampled by repetition, an
    export that doubled its rows): read as it is, its noise would count twice, and every
    covariance and bootstrap interval would claim data the trial does not hold. Where the
    file's coordinates are coarse for its motion (an integer C3D, a TRC of one decimal), so
    that elsewhere more than :data:`_CHANCE_REPEATS` of them repeat the frame before, a still
    subject repeats frames by chance, and nothing is refused."""
    markers = recording.markers
    later, earlier = markers[1:], markers[:-1]
    equal = later == earlier
    same = (equal | (np.isnan(later) & np.isnan(earlier))).all(axis=(1, 2))
    seen = np.isfinite(later[..., 0]).sum(axis=1)
    repeats = np.flatnonzero(same & (seen >= 3))
    if repeats.size == 0:
        return recording
    others = ~same[:, None, None] & np.isfinite(later) & np.isfinite(earlier)
    if others.any() and equal[others].mean() > _CHANCE_REPEATS:
        return recording
    row = int(repeats[0]) + 1
    raise ValueError(
        f"{recording.source}: {recording.when(row)} repeats {recording.when(row - 1)} to the "
        f"last bit in all {int(seen[row - 1])} markers; "
        + (
            "1 frame in all repeats the one before it"
            if repeats.size == 1
            else f"{repeats.size} frames in all repeat the one before them"
        )
        + ": frames written twice, whose noise would count twice; remove the repeated frames"
    )


#: The share of coordinates equal to the frame before's, over the frames that do not repeat,
#: above which a file's resolution lets a still subject repeat a frame by chance (the knee
#: trial's float coordinates: 0.13 %).
_CHANCE_REPEATS = 0.01


def _check_csv_fields(path: Path, content: bytes, header: list[str]) -> None:
    """``ValueError`` naming the first line of ``path``, whose bytes are ``content``
    (:func:`_text_bytes`), with fewer fields than ``header``, or its last line when the file
    ends inside it right after a separator (:func:`_check_cut_after_separator`)."""
    last_field = []
    with io.TextIOWrapper(io.BytesIO(content), encoding="utf-8-sig", newline="") as file:
        records = csv.reader(file)
        next(records)
        for record in records:
            if record and len(record) < len(header):
                line = records.line_num
                last = file.read(1) == ""
                raise _short_row(path, line, len(record), len(header), ", ".join(header), last)
            if record:
                last_field.append(record[len(header) - 1])
        line = records.line_num
    if last_field:
        _check_last_field(path, line, last_field, header[-1])


def _check_csv_extra_fields(path: Path, header: list[str]) -> None:
    """``ValueError`` naming the first line and column of ``path`` that writes a value past the
    ``header``'s columns: a column without a name, or a number split in two by a decimal comma,
    which pandas would drop unseen. Empty fields past them (a separator ending each row) are
    allowed."""
    with path.open(newline="", encoding="utf-8-sig") as file:
        records = csv.reader(file)
        next(records)
        for record in records:
            extra = [i for i, text in enumerate(record[len(header) :], len(header)) if text.strip()]
            if extra:
                raise ValueError(
                    f"{path}: line {records.line_num}, column {extra[0] + 1}: "
                    f"{record[extra[0]].strip()!r} lies past the header's {len(header)} columns "
                    f"({', '.join(header)}); name its column in the header, or remove it (a "
                    "decimal comma splits a number in two: write 1.5, not 1,5)"
                )


# pandas' default missing-value words (``read_csv``'s ``na_values``), kept for the numeric
# columns when the marker column is read without them.
_NA_TEXT = (
    "", "#N/A", "#N/A N/A", "#NA", "-1.#IND", "-1.#QNAN", "-NaN", "-nan", "1.#IND", "1.#QNAN",
    "<NA>", "N/A", "NA", "NULL", "NaN", "None", "n/a", "nan", "null",
)  # fmt: skip

# Frame numbers beyond this are not integers a float64 holds exactly, far past any recording.
_MAX_FRAME = 2**53


def _csv_line(path: Path, row: int, column: str) -> tuple[str, str]:
    """Where data row ``row`` (0-based, as pandas counts it: blank and whitespace-only lines
    skipped) is in ``path``, ``"line 7"`` (1-based), and the text written in its field
    ``column``; for messages only, so the file is read again."""
    with path.open(newline="", encoding="utf-8-sig") as file:
        records = csv.reader(file)
        written = (r for r in records if r and (len(r) > 1 or r[0].strip()))
        header = next(written, [])
        index = header.index(column) if column in header else len(header)
        for seen, record in enumerate(written):
            if seen == row:
                text = record[index] if index < len(record) else ""
                return f"line {records.line_num}", text
    return f"data row {row + 1}", ""  # not reached: pandas read that row


def _csv_frame_numbers(frames: pd.Series, path: Path) -> np.ndarray:
    """The ``frame`` column (n,), its text as written (a missing-value word NaN), as frame
    numbers (n,) int64 by the TRC's rule (:func:`_whole_number`); ``ValueError`` naming the
    line of a value that is not one (or lies beyond 2**53; the header's own ``frame``, repeated
    where files were joined, is named as such), or a range of numbers so much wider than the
    frames present that it is not frame numbers."""
    # Each distinct text is read once: a long file writes every frame number once per marker.
    codes, texts = pd.factorize(frames)
    read = [_whole_number(text) for text in texts]
    # -1 marks a text that is no frame number; it is also the value for code -1 (NaN, a
    # missing-value word), which indexes the last element.
    known = [-1 if n is None or n > _MAX_FRAME else n for n in read]
    numbers = np.array([*known, -1], dtype=np.int64)[codes]
    bad = numbers < 0
    if bad.any():
        row = int(np.argmax(bad))
        line, text = _csv_line(path, row, "frame")
        if text.strip() == "frame":
            with path.open(encoding="utf-8-sig") as file:
                header = file.readline().strip()
            raise ValueError(
                f"{path}: {line} repeats the header ({header}): files joined end to end? Remove "
                "the line, and read each recording from a file of its own"
            )
        if codes[row] < 0 or read[codes[row]] is None:
            raise _not_a_frame_number(path, line, "frame", text)
        raise ValueError(
            f"{path}: {line}, field frame: {text!r} is beyond any recording (frame numbers up "
            f"to {_MAX_FRAME})"
        )
    span, present = int(numbers.max() - numbers.min()) + 1, len(np.unique(numbers))
    if span > 100 * present + 1000:
        raise ValueError(
            f"{path}: frame numbers run from {numbers.min()} to {numbers.max()} but only "
            f"{present} frames have rows; is the 'frame' column a frame number?"
        )
    return numbers


def _natural(label: str) -> tuple:
    """Sort key placing ``"2"`` before ``"10"`` (marker names written as integers)."""
    return (0, int(label), label) if re.fullmatch(r"-?[0-9]+", label) else (1, 0, label)
