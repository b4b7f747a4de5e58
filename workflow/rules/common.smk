# Helpers shared by the rules: config validation, the condition grid and file lists.
from snakemake.utils import validate

from jointbench.study import config as jb_config
from jointbench.study.studies import get_study

validate(config, "../../config/schema/config.schema.yaml")

STUDIES = jb_config.study_names(config)
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


def all_targets():
    targets = []
    for study in STUDIES:
        targets.append(f"results/collected/{study}.parquet")
        targets.extend(STUDY_TARGETS.get(study, []))
    return targets
