"""A claim that words its own lack is held to its paper's declarations too.

Beside the selections of :mod:`jointbench.papers.common`, a claim check may raise
:class:`~jointbench.papers.common.NotMeasured` itself ("BC is not in this run at the M set",
"local minima not recorded in this run"). Such a site names, in ``lacks``, what it selected by:
a misspelt method, level or column there is the check's mistake (a ``RuntimeError`` naming the
claim), not a run without it, which would leave the claim silently unmeasured on every run.

Each case below misspells one name a real check selects by, in the check's own source, and
measures the full synthetic grid, which holds everything the correct spelling asks for.
"""

from __future__ import annotations

import ast
import inspect
import textwrap
from pathlib import Path

import claim_worlds
import pandas as pd
import pytest

import jointbench.papers
from jointbench.papers import paper_a, paper_b, paper_c, paper_sta
from jointbench.papers.common import NotMeasured, rows_at

MODULES = {"A": paper_a, "B": paper_b, "C": paper_c, "S": paper_sta}


documents = claim_worlds.documents_fixture(MODULES)
worlds = claim_worlds.worlds_fixture()


def _misspelt(module, name: str, spelt: str, typo: str):
    """``module``'s function ``name`` compiled again with the text literal ``spelt``
    replaced by ``typo`` wherever the function's source has it."""
    source = textwrap.dedent(inspect.getsource(getattr(module, name)))
    assert f'"{spelt}"' in source, f"{name} selects by no {spelt!r}"
    namespace = dict(vars(module))
    code = compile(source.replace(f'"{spelt}"', f'"{typo}"'), module.__file__, "exec")
    exec(code, namespace)
    return namespace[name]


#: Per case: the paper, the check (a function of its module), the name it selects by, its
#: misspelling, and the claim the error names.
MISSPELT = {
    "A2's method": ("A", "_a2", "BC", "Bc", "A2"),
    "A2's marker set": ("A", "_a2", "M", "m", "A2"),
    "A3's marker set": ("A", "_a3", "M", "N", "A3"),
    "A4's excepted marker set": ("A", "_a4", "M", "m", "A4"),
    "A7's method": ("A", "_a7", "IS", "Is", "A7"),
    "A9's method": ("A", "_a9", "LS", "Ls", "A9"),
    "A9's marker set": ("A", "_a9", "H", "h", "A9"),
    "A11's largest": ("A", "example_ordering_share", "LS", "LSQ", "A11"),
    "A11's smallest": ("A", "example_ordering_share", "NM", "Nm", "A11"),
    "A12's method": ("A", "_fastest", "NM", "nm", "A12"),
    "B2's method": ("B", "_b2", "planar", "plannar", "B2"),
    "B3's method": ("B", "_b3", "combined", "combned", "B3"),
    "B4's method": ("B", "_b4", "radial", "radal", "B4"),
    "B5's protocol": ("B", "_b5", "mcp", "MCP", "B5"),
    "S7's method": ("S", "_s7", "SCoRE", "score", "S7"),
}


@pytest.mark.parametrize("case", MISSPELT)
def test_a_misspelt_name_in_a_check_is_raised_naming_the_claim(
    documents, worlds, monkeypatch, case
):
    letter, name, spelt, typo, claim = MISSPELT[case]
    module = MODULES[letter]
    misspelt = _misspelt(module, name, spelt, typo)
    if module._CLAIMS.get(claim) is getattr(module, name):
        monkeypatch.setitem(module._CLAIMS, claim, misspelt)
    # Also where measure or another check calls it by name (A2, A11, A12).
    monkeypatch.setattr(module, name, misspelt)
    with pytest.raises(RuntimeError, match=rf"^claim {claim}: ") as raised:
        claim_worlds.measure(letter, documents, worlds[letter])
    assert repr(typo) in str(raised.value)
    assert isinstance(raised.value.__cause__, NotMeasured)


#: Per case: the paper, a module constant a check selects by, its mistaken value, the claim
#: the error names first and what it names.
MISTAKEN_CONSTANTS = {
    "paper C's method": ("C", (paper_c.draw, "METHOD"), "gauss-markv", "C1", "'gauss-markv'"),
    "C1's longest Nt": ("C", (paper_c, "FALL_TO"), 1199, "C1", "n_frames 1199"),
    "C2's reference Nt": ("C", (paper_c, "REFERENCE_NT"), 1000, "C2", "n_frames 1000"),
    "B3's low ratios": ("B", (paper_b, "LOW_RATIOS"), (0.1, 0.35), "B3", "aa_ratio 0.35"),
    "A7's column": ("A", (paper_a, "LOCAL_MINIMUM"), "local_minimun", "A7", "'local_minimun'"),
}


@pytest.mark.parametrize("case", MISTAKEN_CONSTANTS)
def test_a_mistaken_name_a_check_selects_by_is_raised_naming_the_claim(
    documents, worlds, monkeypatch, case
):
    letter, (owner, constant), value, claim, named = MISTAKEN_CONSTANTS[case]
    monkeypatch.setattr(owner, constant, value)
    with pytest.raises(RuntimeError, match=rf"^claim {claim}: asks for ") as raised:
        claim_worlds.measure(letter, documents, worlds[letter])
    assert named in str(raised.value)


def test_paper_a_table2_reading_a_misspelt_column_is_raised(documents, worlds, monkeypatch):
    """Table 2's values are not claims, but their lack is held as a claim's is."""
    misspelt = _misspelt(paper_a, "_our_times", "seconds", "secnds")
    monkeypatch.setattr(paper_a, "_our_times", misspelt)
    with pytest.raises(RuntimeError, match=r"^Table 2 \(A-T2\): asks for recorded column 'secnds'"):
        claim_worlds.measure("A", documents, worlds["A"])


def _raised_without_lacks(path: Path) -> list[str]:
    """Where the module at ``path`` raises NotMeasured without saying what it lacks."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not (isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call)):
            continue
        call = node.exc
        if getattr(call.func, "id", None) != "NotMeasured":
            continue
        if len(call.args) < 2 and not any(k.arg == "lacks" for k in call.keywords):
            found.append(f"{path.name}:{node.lineno}")
    return found


def test_every_lack_a_paper_words_says_what_it_selected_by():
    """Each NotMeasured of the package's papers names its lacks ({} where what it lacks has no
    name), so the declarations are read at every site, not only at the selections'."""
    folder = Path(jointbench.papers.__file__).parent
    sites = [site for path in sorted(folder.glob("*.py")) for site in _raised_without_lacks(path)]
    assert not sites


def test_a_selection_of_rows_says_what_the_run_lacks_by_key():
    table = pd.DataFrame({"method": ["LS", "NM"], "marker_set": ["M", "H"]})
    assert rows_at(table, method="LS", marker_set="M").index.tolist() == [0]
    with pytest.raises(NotMeasured, match=r"^this run has no method BC$") as raised:
        rows_at(table, method="BC")
    assert raised.value.lacks == {"method": ("BC",)}
    with pytest.raises(NotMeasured, match=r"^this run has no result at method LS, marker_set H$"):
        rows_at(table, method="LS", marker_set="H")
    with pytest.raises(NotMeasured, match=r"^BC is not in this run at the M set$") as raised:
        rows_at(table, "BC is not in this run at the M set", method="BC", marker_set="M")
    assert raised.value.lacks == {"method": ("BC",), "marker_set": ("M",)}
    with pytest.raises(KeyError):
        rows_at(table, methd="LS")
