from jointbench.study.logs import logging_to
from jointbench.study.run import collect

with logging_to(snakemake.log[0]):
    collect(
        snakemake.wildcards.study,
        snakemake.input.estimates,
        snakemake.output[0],
        datasets=snakemake.input.datasets,
    )
