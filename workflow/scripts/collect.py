from jointbench.study.run import collect

collect(snakemake.wildcards.study, snakemake.input, snakemake.output[0])
