from jointbench import jobs, report

with jobs.job(snakemake):
    tables = {k: v for k, v in snakemake.input.items() if k != "collected"}
    report.write_captions(tables, snakemake.output.captions, snakemake.config)
    report.write_front_page(
        tables, snakemake.input.collected, snakemake.output.front, snakemake.config
    )
