from jointbench.study.run import collect

collect(
    snakemake.wildcards.study,
    snakemake.input.estimates,
    snakemake.output[0],
    datasets=snakemake.input.datasets,
)
