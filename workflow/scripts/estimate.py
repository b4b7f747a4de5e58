from jointbench import jobs
from jointbench.running.run import run_estimate_files

with jobs.job(snakemake):
    run_estimate_files(
        snakemake.config,
        snakemake.params.study,
        snakemake.wildcards.method,
        snakemake.input.datasets,
        snakemake.output,
        provenance=jobs.provenance(snakemake),
        poses=snakemake.input.poses,
    )
