from jointbench.study.run import run_estimate_files

run_estimate_files(
    snakemake.config,
    snakemake.params.study,
    snakemake.wildcards.method,
    snakemake.input,
    snakemake.output,
)
