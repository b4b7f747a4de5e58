from jointbench import jobs
from jointbench.running.collected import collect

with jobs.job(snakemake):
    collect(
        snakemake.wildcards.study,
        snakemake.input.estimates,
        snakemake.output[0],
        datasets=snakemake.input.datasets,
        provenance=jobs.provenance(snakemake),
        placements=snakemake.input.placements,
        blinds=snakemake.input.blinds,
    )
