from jointbench import jobs, pipeline

with jobs.job(snakemake):
    pipeline.check_published(dict(snakemake.input.items()), snakemake.output, snakemake.config)
