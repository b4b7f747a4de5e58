from pathlib import Path

from jointbench import jobs, report

with jobs.job(snakemake):
    inputs = dict(snakemake.input.items())
    shown = {k.removeprefix("shown__"): v for k, v in inputs.items() if k.startswith("shown__")}
    tables = {k: v for k, v in inputs.items() if k != "collected" and "__" not in k}
    report.write_captions(tables, snakemake.output.captions, snakemake.config)
    captions = {Path(path).stem: path for path in snakemake.output.captions}
    titles = {name: report.output_title(name) for name in shown}
    report.write_pages(shown, captions, titles, snakemake.output.pages)
    report.write_front_page(
        tables, snakemake.input.collected, snakemake.output.front, snakemake.config
    )
