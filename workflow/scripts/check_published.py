from jointbench import jobs, pipeline

with jobs.job(snakemake):
    # The published-values files are inputs so that an edit reruns the check; they are read
    # through the paper registry.
    collected = {k: v for k, v in snakemake.input.items() if k != "published"}
    pipeline.check_published(collected, snakemake.output, snakemake.config)
