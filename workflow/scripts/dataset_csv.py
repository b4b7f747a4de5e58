from jointbench import jobs
from jointbench.resultfiles.interchange import write_dataset_csv

with jobs.job(snakemake):
    write_dataset_csv(snakemake.input[0], snakemake.output[0])
