from jointbench import pipeline

with pipeline.job(snakemake):
    pipeline.render_output(
        snakemake.params.paper,
        snakemake.params.output,
        snakemake.input.collected,
        snakemake.input.datasets,
        snakemake.output,
        snakemake.config,
    )
