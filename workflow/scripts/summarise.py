from jointbench import jobs
from jointbench.running.collected import summarise_estimates

with jobs.job(snakemake):
    summarise_estimates(
        snakemake.wildcards.study,
        snakemake.input.estimates,
        snakemake.output[0],
        datasets=snakemake.input.datasets,
        placements=snakemake.input.placements,
    )
