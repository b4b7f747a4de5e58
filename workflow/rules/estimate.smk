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


rule summarise_estimator:
    """One estimator's mean and median error per condition: `snakemake -j2
    results/summaries/cmc/NM.csv` runs that estimator alone."""
    input:
        lambda w: estimates_files(w.study, [w.method]),
    output:
        "results/summaries/{study}/{method}.csv",
    script:
        "../scripts/summarise.py"


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
