from jointbench.figures import paper_a

paper_a.render(snakemake.rule, snakemake.input, snakemake.output, snakemake.config)
