from jointbench import pipeline

with pipeline.job(snakemake):
    tables = dict(snakemake.input.items())
    pipeline.write_captions(tables, snakemake.output.captions, snakemake.config)
    pipeline.write_front_page(tables, snakemake.output.front, snakemake.config)
