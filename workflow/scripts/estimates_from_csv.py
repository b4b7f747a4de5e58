from jointbench import jobs
from jointbench.resultfiles.interchange import read_estimates_csv

with jobs.job(snakemake):
    read_estimates_csv(
        snakemake.input.estimates,
        snakemake.input.dataset,
        snakemake.output[0],
        provenance=jobs.provenance(snakemake),
    )
