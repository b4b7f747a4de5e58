from jointbench import jobs
from jointbench.resultfiles.parquet import write_blind_dataset

with jobs.job(snakemake):
    # The study's settings stay out of the copy's provenance: its protocol places the truth.
    made_by = {key: value for key, value in jobs.provenance(snakemake).items() if key != "config"}
    write_blind_dataset(snakemake.input[0], snakemake.output[0], provenance=made_by)
