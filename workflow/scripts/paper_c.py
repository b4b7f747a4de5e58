from jointbench.figures import paper_c

paper_c.render(snakemake.rule, snakemake.input, snakemake.output, snakemake.config)
