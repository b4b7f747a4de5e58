from jointbench.study.logs import logging_to
from jointbench.study.run import run_estimate_files

with logging_to(snakemake.log[0]):
    run_estimate_files(
        snakemake.config,
        snakemake.params.study,
        snakemake.wildcards.method,
        snakemake.input,
        snakemake.output,
    )
