"""Code fingerprints: what makes an edited library function rerun the jobs that use it."""

from __future__ import annotations

import importlib.util
import sys

from jointbench.estimators import registry
from jointbench.fingerprint import code_fingerprint

MODULE = """
import numpy as np

SCALE = {scale}
OFFSET = np.array([0.0, 0.0, {offset}])


def helper(x):
    # a comment that does not count
    return x * SCALE


def uses_helper(x):
    return helper(x) + OFFSET


def independent(x):
    return x - 1
"""


def _load(tmp_path, name, **values):
    path = tmp_path / f"{name}.py"
    path.write_text(MODULE.format(**values))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _fingerprints(module):
    prefixes = (module.__name__,)
    return (
        code_fingerprint(module.uses_helper, prefixes=prefixes),
        code_fingerprint(module.independent, prefixes=prefixes),
    )


def test_a_change_reaches_the_functions_that_use_it_and_no_others(tmp_path):
    base = _fingerprints(_load(tmp_path, "jbfp_a", scale=2, offset=0.0))
    same = _fingerprints(_load(tmp_path, "jbfp_a", scale=2, offset=0.0))
    constant = _fingerprints(_load(tmp_path, "jbfp_a", scale=3, offset=0.0))
    array = _fingerprints(_load(tmp_path, "jbfp_a", scale=2, offset=1.0))
    assert base == same
    assert constant[0] != base[0] and constant[1] == base[1]
    assert array[0] != base[0] and array[1] == base[1]


def test_comments_and_line_numbers_do_not_count(tmp_path):
    base = _fingerprints(_load(tmp_path, "jbfp_b", scale=2, offset=0.0))
    path = tmp_path / "jbfp_b.py"
    path.write_text("\n\n# moved down\n" + path.read_text().replace("a comment", "another"))
    spec = importlib.util.spec_from_file_location("jbfp_b", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["jbfp_b"] = module
    spec.loader.exec_module(module)
    assert _fingerprints(module) == base


def test_estimators_have_distinct_stable_fingerprints():
    prints = {
        (kind, name): code_fingerprint(registry.get(kind, name))
        for kind in registry.KINDS
        for name in registry.methods(kind)
    }
    assert len(set(prints.values())) == len(prints)
    again = {key: code_fingerprint(registry.get(*key)) for key in prints}
    assert again == prints


CACHED = """
from functools import lru_cache


@lru_cache(maxsize=4)
def cached_table(n):
    return tuple(range(n * {factor}))


def _source():
    return sum


@lru_cache(maxsize=1)
def compiled():
    # stands for a loader that compiles a plain function of this module on first use
    return _source


def uses_cached(n):
    return cached_table(n), compiled()
"""


def test_functions_behind_a_cache_count(tmp_path):
    """A helper wrapped by functools.lru_cache (a lookup table, a compiled kernel's loader) is
    part of the code of the functions that call it."""

    def fingerprint(factor: int, source: str = "sum") -> str:
        path = tmp_path / "jbfp_c.py"
        path.write_text(CACHED.format(factor=factor).replace("return sum", f"return {source}"))
        spec = importlib.util.spec_from_file_location("jbfp_c", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules["jbfp_c"] = module
        spec.loader.exec_module(module)
        return code_fingerprint(module.uses_cached, prefixes=("jbfp_c",))

    base = fingerprint(2)
    assert fingerprint(2) == base
    assert fingerprint(3) != base
    assert fingerprint(2, source="max") != base


def test_nm_fingerprint_reaches_its_cached_constraint_matrix():
    from jointbench.estimators import sphere
    from jointbench.fingerprint import reached
    from jointbench.numerics import poses

    assert sphere._nm_constraint.__wrapped__ in reached([registry.get("center", "NM")])
    assert poses._horn_rotations.__wrapped__ in reached([poses.rigid_poses])


def test_a_kernels_compile_options_count():
    """The class that compiles a kernel (its Numba options) is part of the kernel's code."""
    from jointbench.fingerprint import reached
    from jointbench.numerics import compiled, poses

    assert compiled._Kernel in reached([poses.rigid_poses])
