"""A paper's published table is whole: a cell deleted from its published values is an error
naming the paper, the table and the cell, not one comparison fewer.

Which cells a table has is the paper's own definition (``Paper.tables``: its rows and columns
as printed, less the cells it leaves empty); the published values must list each.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from jointbench.comparison.published import load_published
from jointbench.papers import get_paper, paper_names

#: (paper, table): the papers' tables whose cells are published values.
TABLES = [(name, table.source) for name in paper_names() for table in get_paper(name).tables]


def _table(paper_name: str, source: str):
    (table,) = [t for t in get_paper(paper_name).tables if t.source == source]
    return table


def _load(paper, path=None):
    return load_published(path or paper.published, paper.declares, paper.tables)


def test_the_papers_with_tables_of_values_declare_them():
    assert {(paper, source) for paper, source in TABLES} >= {
        ("paper_a", "Table 1"),
        ("paper_a", "Table 2"),
        ("paper_b", "Table 1"),
        ("paper_c", "Table 1"),
    }
    assert len(_table("paper_b", "Table 1").cells) == 72  # 6 rows × 12 columns, as printed
    assert len(_table("paper_c", "Table 1").cells) == 17  # v at Nt = 1200 is left empty


@pytest.mark.parametrize("name", paper_names())
def test_the_shipped_files_are_whole(name):
    paper = get_paper(name)
    listed = {entry["id"] for entry in _load(paper).get("values", [])}
    for table in paper.tables:
        assert set(table.cells) <= listed
        sources = {e["source"] for e in _load(paper)["values"] if e["id"] in table.cells}
        assert sources == {table.source}, (table.source, sources)


@pytest.mark.parametrize("position", ["first", "middle", "last"])
@pytest.mark.parametrize(("name", "source"), TABLES)
def test_a_cell_deleted_from_a_table_is_named(tmp_path, name, source, position):
    paper = get_paper(name)
    cells = _table(name, source).cells
    cell = cells[{"first": 0, "middle": len(cells) // 2, "last": -1}[position]]
    document = yaml.safe_load(paper.published.read_text())
    document["values"] = [entry for entry in document["values"] if entry["id"] != cell]
    path = tmp_path / paper.published.name
    path.write_text(yaml.safe_dump(document, allow_unicode=True, sort_keys=False))
    with pytest.raises(ValueError) as raised:
        _load(paper, path)
    message = str(raised.value)
    assert f"paper {paper.letter} {source}" in message, message
    assert cell in message, message
    assert str(path) in message, message


#: (paper, table, cell): a cell of each table whose cells list several numbers.
LIST_CELLS = [
    (name, table.source, table.cells[0])
    for name in paper_names()
    for table in get_paper(name).tables
    if table.lists
]


def test_paper_a_table_1_cells_list_the_three_markers():
    table = _table("paper_a", "Table 1")
    # 2 rows (marker sets) × 3 columns (marker number), each row kept in one cell
    assert (len(table.cells), len(table.lists)) == (2, 3)
    assert ("paper_a", "Table 1", "A-T1-M") in LIST_CELLS


def _deleted(numbers, at):
    return numbers[:at] + numbers[at + 1 :]


#: An edit of a list-valued cell of ``n`` numbers, and the position its error names: where the
#: list ends short, the number that is not one, the number too many.
LIST_EDITS = {
    "first deleted": (lambda numbers: numbers[1:], lambda n: n),
    "middle deleted": (lambda numbers: _deleted(numbers, len(numbers) // 2), lambda n: n),
    "last deleted": (lambda numbers: numbers[:-1], lambda n: n),
    "one replaced by null": (lambda numbers: [numbers[0], None, *numbers[2:]], lambda n: 2),
    "one added": (lambda numbers: [*numbers, numbers[-1]], lambda n: n + 1),
}


def _rewritten(tmp_path, paper, cell, change) -> Path:
    document = yaml.safe_load(paper.published.read_text())
    for entry in document["values"]:
        if entry["id"] == cell:
            entry["published"] = change(entry["published"])
    path = tmp_path / paper.published.name
    path.write_text(yaml.safe_dump(document, allow_unicode=True, sort_keys=False))
    return path


@pytest.mark.parametrize("edit", LIST_EDITS)
@pytest.mark.parametrize(("name", "source", "cell"), LIST_CELLS)
def test_a_number_deleted_from_a_list_valued_cell_is_named(tmp_path, name, source, cell, edit):
    paper = get_paper(name)
    change, position = LIST_EDITS[edit]
    path = _rewritten(tmp_path, paper, cell, change)
    with pytest.raises(ValueError) as raised:
        _load(paper, path)
    message = str(raised.value)
    at = f"position {position(len(_table(name, source).lists))}"
    for part in (str(path), f"paper {paper.letter} {source} cell {cell}:", at):
        assert part in message, message


def test_a_single_number_cell_replaced_by_null_is_named(tmp_path):
    paper = get_paper("paper_b")
    cell = _table("paper_b", "Table 1").cells[0]
    path = _rewritten(tmp_path, paper, cell, lambda number: None)
    with pytest.raises(ValueError, match=f"paper B Table 1 cell {cell}: None is not a number"):
        _load(paper, path)
