from jointbench.study.logs import logging_to
from jointbench.study.run import run_simulate_files

with logging_to(snakemake.log[0]):
    run_simulate_files(snakemake.config, snakemake.params.study, snakemake.output)
