rule simulate:
    """Synthetic trials of one condition of a study, with ground truth in the metadata."""
    output:
        "results/datasets/{study}/{condition}.parquet",
    log:
        "results/logs/simulate/{study}/{condition}.log",
    script:
        "../scripts/simulate.py"
