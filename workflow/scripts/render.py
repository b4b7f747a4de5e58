from jointbench import jobs, pipeline

with jobs.job(snakemake):
    pipeline.render_output(
        snakemake.params.paper,
        snakemake.params.output,
        snakemake.input.collected,
        snakemake.input.datasets,
        snakemake.output,
        snakemake.config,
    )
