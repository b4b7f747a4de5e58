from jointbench import jobs
from jointbench.ensembles.verdicts import write_summary

with jobs.job(snakemake):
    write_summary(snakemake.input.members, snakemake.input.published, snakemake.output)
