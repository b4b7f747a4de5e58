from jointbench import pipeline

with pipeline.job(snakemake):
    pipeline.check_published(dict(snakemake.input.items()), snakemake.output, snakemake.config)
