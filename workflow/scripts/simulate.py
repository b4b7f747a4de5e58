from jointbench.study.run import run_simulate_files

run_simulate_files(snakemake.config, snakemake.params.study, snakemake.output)
