from jointbench import jobs, pipeline

with jobs.job(snakemake):
    pipeline.render_paper(
        snakemake.params.paper,
        snakemake.params.outputs,
        snakemake.input.collected,
        snakemake.input.datasets,
        dict(snakemake.output.items()),
        snakemake.config,
    )
