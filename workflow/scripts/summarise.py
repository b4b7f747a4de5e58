import pandas as pd

from jointbench.study.io import read_table
from jointbench.study.summary import summarise

estimates = pd.concat([read_table(path) for path in snakemake.input], ignore_index=True)
summarise(estimates, snakemake.wildcards.study).to_csv(snakemake.output[0], index=False)
