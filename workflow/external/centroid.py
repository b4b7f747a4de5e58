"""centroid: the mean of every marker position of a trial as its "centre" (a template, not a
method), run by ``workflow/rules/estimators/centroid.smk``. Plain pandas and pyarrow, no
jointbench: what any external estimator reads and writes."""

import json
import time

import pandas as pd
import pyarrow.parquet as pq

dataset, estimates = snakemake.input[0], snakemake.output[0]
meta = json.loads(pq.read_schema(dataset).metadata[b"jointbench"])
rows = []
for trial, markers in pd.read_parquet(dataset).groupby("trial"):
    start = time.perf_counter()
    center = markers[["x", "y", "z"]].to_numpy().mean(axis=0)
    rows.append(
        {
            **meta["condition"],
            "trial": trial,
            "method": "centroid",
            "center_x": center[0],
            "center_y": center[1],
            "center_z": center[2],
            "converged": True,
            "iterations": 0,
            "seconds": time.perf_counter() - start,
            "status": "ok",
        }
    )
pd.DataFrame(rows).to_parquet(estimates, index=False)
