# One job per (study, built-in estimator) runs it over every condition's dataset and writes one
# estimates file per condition. A user's rule for an external estimator may produce the same
# files one condition at a time; the method wildcard of these rules only matches built-ins.
for _study in STUDIES:

    rule:
        name:
            f"estimate_{_study}"
        input:
            expand(
                "results/datasets/{study}/{condition}.parquet",
                study=_study,
                condition=condition_ids(_study),
            ),
        output:
            expand(
                "results/estimates/{study}/{{method}}/{condition}.parquet",
                study=_study,
                condition=condition_ids(_study),
            ),
        log:
            f"results/logs/estimate/{_study}/{{method}}.log",
        wildcard_constraints:
            method=_alternatives(
                jb_config.estimator_names(config, _study, source="builtin")
            ),
        params:
            study=_study,
            code=estimate_code(_study),
        script:
            "../scripts/estimate.py"


rule summarise_estimator:
    """One estimator's mean and median error per condition: `snakemake -j2
    results/summaries/cmc/NM.csv` runs that estimator alone."""
    input:
        lambda w: estimates_files(w.study, [w.method]),
    output:
        "results/summaries/{study}/{method}.csv",
    log:
        "results/logs/summarise/{study}/{method}.log",
    params:
        code=code_fingerprint(pipeline.summarise_estimates),
    script:
        "../scripts/summarise.py"


rule collect:
    """All estimates of a study in one table, each file's schema checked first and each held
    to its condition's dataset (same trials, each once, same condition values)."""
    input:
        estimates=lambda w: estimates_files(w.study),
        datasets=lambda w: [
            dataset_file(w.study, c) for c in jb_config.conditions(config, w.study)
        ],
    output:
        "results/collected/{study}.parquet",
    log:
        "results/logs/collect/{study}.log",
    params:
        code=code_fingerprint(jb_run.collect),
    script:
        "../scripts/collect.py"
