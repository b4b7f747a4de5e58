from jointbench.study.published import run_check

run_check(dict(snakemake.input.items()), snakemake.output, snakemake.config)
