from jointbench import jobs
from jointbench.ensembles.members import run_member

with jobs.job(snakemake):
    rows = run_member(snakemake.config, snakemake.params.study, int(snakemake.wildcards.member))
    rows.to_csv(snakemake.output[0], index=False)
