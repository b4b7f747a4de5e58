from jointbench.figures import paper_b

paper_b.render(snakemake.rule, snakemake.input, snakemake.output, snakemake.config)
