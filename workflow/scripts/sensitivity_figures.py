from jointbench import jobs
from jointbench.figures.sensitivity import draw_figures

with jobs.job(snakemake):
    draw_figures(
        snakemake.input.rows,
        snakemake.input.curves,
        list(snakemake.params.settings["named"]),
        snakemake.output,
    )
