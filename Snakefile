# jointbench: regenerate every dataset, estimate, figure and table with `snakemake -j2`.
from pathlib import Path

from snakemake.utils import min_version

min_version("8.20")


configfile: "config/config.yaml"


include: "workflow/rules/common.smk"


rule all:
    input:
        all_targets(),
    default_target: True


# `snakemake -j2 study_cmc` (or study_hinge, study_hip) regenerates one study alone.
for _study in STUDIES:

    rule:
        name:
            f"study_{_study}"
        input:
            study_targets(_study),


include: "workflow/rules/simulate.smk"
include: "workflow/rules/estimate.smk"


# Estimators outside the package: each file here holds the rule of one external estimator.
for _rules in sorted(Path(workflow.basedir, "workflow", "rules", "estimators").glob("*.smk")):

    include: _rules


include: "workflow/rules/paper_a.smk"
include: "workflow/rules/paper_b.smk"
include: "workflow/rules/paper_c.smk"
include: "workflow/rules/check.smk"
include: "workflow/rules/extended.smk"
