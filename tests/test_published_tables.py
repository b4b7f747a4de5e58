"""A paper's published table is whole: a cell deleted from its published values is an error
naming the paper, the table and the cell, not one comparison fewer.

Which cells a table has is the paper's own definition (``Paper.tables``: its rows and columns
as printed, less the cells it leaves empty); the published values must list each.
"""

from __future__ import annotations

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
