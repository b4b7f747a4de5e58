from jointbench import pipeline
from jointbench.study.run import run_estimate_files

with pipeline.job(snakemake):
    run_estimate_files(
        snakemake.config,
        snakemake.params.study,
        snakemake.wildcards.method,
        snakemake.input,
        snakemake.output,
        provenance=pipeline.provenance(snakemake),
    )
