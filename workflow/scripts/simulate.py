from jointbench.study.config import parse_condition_id
from jointbench.study.run import run_simulate

study = snakemake.wildcards.study
condition = parse_condition_id(snakemake.config, study, snakemake.wildcards.condition)
run_simulate(snakemake.config, study, condition, snakemake.output[0])
