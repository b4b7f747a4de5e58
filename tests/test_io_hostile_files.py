"""Files a lab meets that are not what their name or header says: a binary file under a text
extension, a C3D of more frames than its parameters count, one with no markers at all, and an
output path that cannot be written, each refused naming the file and what is wrong with it."""

from __future__ import annotations

import pytest
from test_io_recordings import KNEE

from jointbench.io import read


@pytest.mark.parametrize(
    ("name", "content", "what"),
    [
        ("knee.csv", None, "CSV text: its first bytes are a C3D file's; name it .c3d"),
        ("knee.trc", None, "TRC text: its first bytes are a C3D file's; name it .c3d"),
        (
            "markers.csv",
            b"PK\x03\x04\x14\x00\x00\x00frame,marker,x,y,z\n",  # a zip, as .xlsx is
            "CSV text: byte 2 is 0x03, a control character no text holds (a spreadsheet, or "
            "another program's own format? export it as CSV)",
        ),
    ],
    ids=["c3d-as-csv", "c3d-as-trc", "zip-as-csv"],
)
def test_a_binary_file_under_a_text_extension_is_named_as_binary(tmp_path, name, content, what):
    """Read as text, a C3D's bytes (``content`` None: the knee trial's) were refused as "not
    UTF-8 text; save the file as UTF-8", a remedy no binary file takes."""
    path = tmp_path / name
    path.write_bytes(KNEE.read_bytes() if content is None else content)
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value) == f"{path}: a binary file, not {what}"


def test_a_utf16_text_file_is_refused_as_text_not_in_utf8(tmp_path):
    path = tmp_path / "markers.csv"
    path.write_text("frame,marker,x,y,z\n0,A,1,2,3\n", encoding="utf-16")
    with pytest.raises(ValueError, match="is not UTF-8 text; save the file as UTF-8"):
        read(path)


def test_text_with_tabs_and_line_ends_is_text(tmp_path):
    path = tmp_path / "markers.csv"
    path.write_bytes(b"frame,marker,x,y,z\r\n0,A,1,2,3\r\n\t\r\n")
    assert read(path).labels == ("A",)
