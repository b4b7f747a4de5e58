from jointbench import pipeline

with pipeline.job(snakemake):
    pipeline.write_captions(dict(snakemake.input.items()), snakemake.output, snakemake.config)
