from jointbench.figures import extended

extended.render(snakemake.rule, snakemake.input, snakemake.output, snakemake.config)
