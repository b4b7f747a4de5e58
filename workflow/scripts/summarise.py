import pandas as pd

from jointbench.study.summary import summarise

estimates = pd.concat([pd.read_parquet(path) for path in snakemake.input], ignore_index=True)
summarise(estimates, snakemake.wildcards.study).to_csv(snakemake.output[0], index=False)
