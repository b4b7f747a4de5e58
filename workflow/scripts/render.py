from jointbench import jobs, pipeline

with jobs.job(snakemake):
    pipeline.render_study(
        snakemake.params.study,
        snakemake.params.papers,
        snakemake.input.collected,
        snakemake.input.datasets,
        dict(snakemake.output.items()),
        snakemake.config,
    )
