from jointbench import jobs, pipeline

with jobs.job(snakemake):
    for what in ("table", "figure"):
        pipeline.render_extended(
            snakemake.params.study,
            snakemake.input[0],
            snakemake.output,
            snakemake.config,
            what=what,
        )
