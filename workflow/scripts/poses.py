from jointbench import jobs
from jointbench.running.run import run_poses_files

with jobs.job(snakemake):
    run_poses_files(
        snakemake.params.study,
        snakemake.input,
        snakemake.output,
        provenance=jobs.provenance(snakemake),
    )
