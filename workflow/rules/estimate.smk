rule estimate:
    """Run one built-in estimator over every trial of one dataset file."""
    input:
        "results/datasets/{study}/{condition}.parquet",
    output:
        "results/estimates/{study}/{method}/{condition}.parquet",
    wildcard_constraints:
        method=_alternatives(BUILTIN),
    log:
        "results/logs/estimate/{study}/{method}/{condition}.log",
    script:
        "../scripts/estimate.py"


rule collect:
    """All estimates of a study in one table, each file's schema checked first."""
    input:
        lambda w: estimates_files(w.study),
    output:
        "results/collected/{study}.parquet",
    log:
        "results/logs/collect/{study}.log",
    script:
        "../scripts/collect.py"
