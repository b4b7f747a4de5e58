from jointbench.study.run import run_estimate

run_estimate(
    snakemake.config,
    snakemake.wildcards.study,
    snakemake.wildcards.method,
    snakemake.input[0],
    snakemake.output[0],
)
