from jointbench import pipeline
from jointbench.study.run import collect

with pipeline.job(snakemake):
    collect(snakemake.wildcards.study, snakemake.input, snakemake.output[0])
