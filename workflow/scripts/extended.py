from jointbench import pipeline

with pipeline.job(snakemake):
    pipeline.render_extended(
        snakemake.params.study,
        snakemake.input[0],
        snakemake.output,
        snakemake.config,
        what=snakemake.params.what,
    )
