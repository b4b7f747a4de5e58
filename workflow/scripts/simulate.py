from jointbench import pipeline
from jointbench.study.run import run_simulate_files

with pipeline.job(snakemake):
    run_simulate_files(
        snakemake.config,
        snakemake.params.study,
        snakemake.output,
        provenance=pipeline.provenance(snakemake),
    )
