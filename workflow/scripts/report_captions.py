from jointbench.figures.captions import write_captions

tables = {name: path for name, path in snakemake.input.items() if name != "descriptions"}
write_captions(snakemake.input.descriptions, tables, snakemake.output)
