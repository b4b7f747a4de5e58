from jointbench import pipeline
from jointbench.study.run import collect

with pipeline.job(snakemake):
    collect(
        snakemake.wildcards.study,
        snakemake.input.estimates,
        snakemake.output[0],
        datasets=snakemake.input.datasets,
        provenance=pipeline.provenance(snakemake),
    )
