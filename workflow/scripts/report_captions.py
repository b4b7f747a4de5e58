from jointbench import pipeline

with pipeline.job(snakemake):
    tables = {k: v for k, v in snakemake.input.items() if k != "collected"}
    pipeline.write_captions(tables, snakemake.output.captions, snakemake.config)
    pipeline.write_front_page(
        tables, snakemake.input.collected, snakemake.output.front, snakemake.config
    )
