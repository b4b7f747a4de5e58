# jointbench: regenerate every dataset, estimate, figure and table with `snakemake -j2`.
from pathlib import Path

from snakemake.utils import min_version

min_version("8.20")


configfile: "config/config.yaml"


# The report's landing page is written by the report_captions rule (workflow/rules/check.smk).
report: "results/report/workflow.rst"


include: "workflow/rules/common.smk"


rule all:
    default_target: True
    input:
        all_targets(),


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
for _rules in sorted(
    Path(workflow.basedir, "workflow", "rules", "estimators").glob("*.smk")
):

    include: _rules


include: "workflow/rules/render.smk"
include: "workflow/rules/check.smk"
include: "workflow/rules/verdicts.smk"
