from jointbench import jobs
from jointbench.resultfiles.interchange import check_dataset_csv, read_estimates_csv

with jobs.job(snakemake):
    check_dataset_csv(snakemake.input.markers, snakemake.input.dataset)
    read_estimates_csv(
        snakemake.input.estimates,
        snakemake.input.dataset,
        snakemake.output[0],
        provenance=jobs.provenance(snakemake),
    )
