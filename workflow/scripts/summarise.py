from jointbench import jobs
from jointbench.study.collected import summarise_estimates

with jobs.job(snakemake):
    summarise_estimates(snakemake.wildcards.study, snakemake.input, snakemake.output[0])
