from jointbench import jobs
from jointbench.resultfiles.parquet import write_blind_dataset
from jointbench.running.placement import dataset_placements, write_placements

with jobs.job(snakemake):
    dataset, settings = snakemake.input[0], snakemake.params.settings
    placements = dataset_placements(
        dataset, settings["base_seed"], settings["blind_placement"]["translation_mm"]
    )
    # The study's settings stay out of the copy's provenance: its protocol places the truth.
    made_by = {key: value for key, value in jobs.provenance(snakemake).items() if key != "config"}
    write_blind_dataset(dataset, snakemake.output.blind, placements, provenance=made_by)
    write_placements(snakemake.output.placements, placements, jobs.provenance(snakemake))
