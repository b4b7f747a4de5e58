from jointbench import pipeline

with pipeline.job(snakemake):
    pipeline.summarise_estimates(snakemake.wildcards.study, snakemake.input, snakemake.output[0])
