from jointbench import jobs
from jointbench.running.run import run_simulate_files

with jobs.job(snakemake):
    run_simulate_files(
        snakemake.config,
        snakemake.params.study,
        snakemake.output,
        provenance=jobs.provenance(snakemake),
    )
