from jointbench import jobs
from jointbench.ensembles.sensitivity import write_summary

with jobs.job(snakemake):
    write_summary(
        snakemake.input.rows, snakemake.input.values, snakemake.input.published, snakemake.output
    )
