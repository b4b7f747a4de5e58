# jointbench: regenerate every dataset, estimate, figure and table with `snakemake -j2`.
from snakemake.utils import min_version

min_version("8.20")


configfile: "config/config.yaml"


include: "workflow/rules/common.smk"


rule all:
    input:
        all_targets(),
    default_target: True


include: "workflow/rules/simulate.smk"
include: "workflow/rules/estimate.smk"
include: "workflow/rules/paper_a.smk"
include: "workflow/rules/paper_b.smk"
include: "workflow/rules/paper_c.smk"
