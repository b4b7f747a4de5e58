# Helpers shared by the rules: config validation, the condition grid and file lists.
from pathlib import Path

from snakemake.utils import validate

from jointbench.study import config as jb_config

validate(config, "../../config/schema/config.schema.yaml")
# Grid values, estimator names and options: a mistake stops the run here, naming the key.
jb_config.check_config(config)

import sys

STUDIES = jb_config.study_names(config)
# The interpreter running this workflow, for external estimators' shell commands.
PYTHON = sys.executable
BUILTIN = sorted({m for s in STUDIES for m in jb_config.estimator_names(config, s, source="builtin")})


def _alternatives(names):
    """A regex matching exactly one of ``names`` (never matches when the list is empty)."""
    import re

    return "|".join(re.escape(n) for n in names) or "(?!)"


wildcard_constraints:
    study=_alternatives(STUDIES),
    condition=r"[A-Za-z0-9_.\-]+",


def condition_ids(study):
    return [jb_config.condition_id(c) for c in jb_config.conditions(config, study)]


def estimates_files(study, methods=None):
    """Every estimates file of a study (optionally only some estimators)."""
    methods = methods or jb_config.estimator_names(config, study)
    return expand(
        "results/estimates/{study}/{method}/{condition}.parquet",
        study=study,
        method=methods,
        condition=condition_ids(study),
    )


STUDY_TARGETS = {
    "cmc": [
        *expand("results/figures/paper_a_{fig}.{ext}", fig=["fig3", "fig4"], ext=["png", "pdf"]),
        *expand("results/tables/paper_a_{table}.{ext}", table=["table2", "claims"], ext=["csv", "md"]),
    ],
    "hinge": [
        *expand("results/figures/paper_b_{fig}.{ext}", fig=["fig2", "fig5"], ext=["png", "pdf"]),
        *expand("results/tables/paper_b_{table}.{ext}", table=["table1", "claims"], ext=["csv", "md"]),
    ],
    "hip": [
        *expand("results/figures/paper_c_uncertainty.{ext}", ext=["png", "pdf"]),
        *expand(
            "results/tables/paper_c_{table}.{ext}",
            table=["table1", "calibration", "claims"],
            ext=["csv", "md"],
        ),
    ],
}


PUBLISHED_TABLES = {
    "cmc": ["paper_a_table2", "paper_a_claims"],
    "hinge": ["paper_b_table1", "paper_b_claims"],
    "hip": ["paper_c_table1", "paper_c_claims"],
}


def caption_tables():
    """Extra tables the report captions summarise."""
    tables = {"published_comparison": "results/tables/published_comparison.csv"}
    tables.update({f"extended_{s}": f"results/tables/extended_{s}.csv" for s in STUDIES})
    if "hip" in STUDIES:
        tables["paper_c_calibration"] = "results/tables/paper_c_calibration.csv"
    return tables


def published_tables():
    """The per-paper tables the published-value check reads, by name."""
    return {
        name: f"results/tables/{name}.csv" for study in STUDIES for name in PUBLISHED_TABLES[study]
    }


CAPTIONS = "results/report/captions/{name}.rst"
CATEGORIES = {
    "extended": "Extended ranking of every estimator",
    "paper_a": "Paper A: centre of rotation",
    "paper_b": "Paper B: axis of rotation",
    "paper_c": "Paper C: hip joint centre",
    "published": "Agreement with the papers",
}


def reported(path, name):
    """``path`` flagged for `snakemake --report`, captioned by results/report/captions/{name}.rst."""
    return report(
        path,
        caption="../../" + CAPTIONS.format(name=name),
        category=CATEGORIES[name[:7] if name.startswith("paper_") else name.split("_")[0]],
    )


def caption_names():
    names = [Path(t).stem for study in STUDIES for t in STUDY_TARGETS.get(study, [])]
    extended = [f"extended_{s}{suffix}" for s in STUDIES for suffix in ("", "_figure")]
    return sorted(set(names)) + extended + ["published_comparison"]


def study_targets(study):
    """The collected results, every figure and table of one study and its extended ranking."""
    extended = [
        *expand("results/tables/extended_{study}.{ext}", study=study, ext=["csv", "md"]),
        *expand("results/figures/extended_{study}.{ext}", study=study, ext=["png", "pdf"]),
    ]
    return [f"results/collected/{study}.parquet", *STUDY_TARGETS.get(study, []), *extended]


def all_targets():
    targets = [target for study in STUDIES for target in study_targets(study)]
    captions = [CAPTIONS.format(name=name) for name in caption_names()]
    return [*targets, "results/tables/published_comparison.csv", *captions]
