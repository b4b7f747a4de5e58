# Built-in estimators run in one of two granularities, chosen by `jobs.estimate` in the config:
# `per_study` (the default: one job per study and estimator over every condition, few fat jobs
# for one machine) or `per_condition` (one job per condition and estimator, enough jobs to fill
# a cluster). Either way each condition has its own estimates file, and editing one estimator
# reruns only its jobs. The method wildcard of these rules only matches built-ins, so a user's
# rule may write an external estimator's files.
#
# A study with two or more pose-based estimators (the hip study's four) fits every trial's poses
# once, in a poses job of the same granularity, and its pose-based estimate jobs read them.
PER_CONDITION = config.get("jobs", {}).get("estimate", "per_study") == "per_condition"


for _study in STUDIES:
    _builtin = _alternatives(
        jb_config.estimator_names(config, _study, source="builtin")
    )
    _shared = jb_run.methods_sharing_poses(config, _study)

    if _shared and PER_CONDITION:

        rule:
            name:
                f"poses_{_study}"
            input:
                f"results/datasets/{_study}/{{condition}}.parquet",
            output:
                f"results/poses/{_study}/{{condition}}.parquet",
            log:
                f"results/logs/poses/{_study}/{{condition}}.log",
            conda:
                "../envs/jointbench.yaml"
            params:
                study=_study,
                code=script_code("poses"),
            message:
                f"poses {_study}: {{wildcards.condition}}"
            script:
                "../scripts/poses.py"

    elif _shared:

        rule:
            name:
                f"poses_{_study}"
            input:
                expand(
                    "results/datasets/{study}/{condition}.parquet",
                    study=_study,
                    condition=condition_ids(_study),
                ),
            output:
                expand(POSES, study=_study, condition=condition_ids(_study)),
            log:
                f"results/logs/poses/{_study}.log",
            conda:
                "../envs/jointbench.yaml"
            params:
                study=_study,
                code=script_code("poses"),
            message:
                f"poses {_study}: {len(condition_ids(_study))} conditions"
            script:
                "../scripts/poses.py"

    if PER_CONDITION:

        rule:
            name:
                f"estimate_{_study}"
            input:
                # A list, as in the per-study rule: the script takes a list of datasets.
                datasets=[f"results/datasets/{_study}/{{condition}}.parquet"],
                poses=shared_poses(_study, _shared, per_condition=True),
            output:
                f"results/estimates/{_study}/{{method}}/{{condition}}.parquet",
            log:
                f"results/logs/estimate/{_study}/{{method}}/{{condition}}.log",
            wildcard_constraints:
                method=_builtin,
            conda:
                "../envs/jointbench.yaml"
            params:
                study=_study,
                code=script_code("estimate"),
                settings=estimate_settings(_study),
            message:
                f"estimate {_study}: {{wildcards.method}} on {{wildcards.condition}}"
            script:
                "../scripts/estimate.py"

    else:

        rule:
            name:
                f"estimate_{_study}"
            input:
                datasets=expand(
                    "results/datasets/{study}/{condition}.parquet",
                    study=_study,
                    condition=condition_ids(_study),
                ),
                poses=shared_poses(_study, _shared),
            output:
                expand(
                    "results/estimates/{study}/{{method}}/{condition}.parquet",
                    study=_study,
                    condition=condition_ids(_study),
                ),
            log:
                f"results/logs/estimate/{_study}/{{method}}.log",
            wildcard_constraints:
                method=_builtin,
            conda:
                "../envs/jointbench.yaml"
            params:
                study=_study,
                code=script_code("estimate"),
                settings=estimate_settings(_study),
            message:
                f"estimate {_study}: {{wildcards.method}} on {len(condition_ids(_study))} conditions"
            script:
                "../scripts/estimate.py"


rule summarise_estimator:
    """One estimator's errors per condition, its files scored against their datasets as collect
    scores them."""
    input:
        estimates=listed_estimates_files,
        datasets=lambda w: [
            dataset_file(w.study, c) for c in jb_config.conditions(config, w.study)
        ],
        placements=lambda w: placements_files(w.study, [w.method]),
    output:
        "results/summaries/{study}/{method}.csv",
    log:
        "results/logs/summarise/{study}/{method}.log",
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("summarise"),
    message:
        "summarise {wildcards.study}: {wildcards.method}"
    script:
        "../scripts/summarise.py"


rule collect:
    """All estimates of a study in one table, each file's schema checked first, each held to
    its condition's dataset (same trials, each once, same condition values), an external
    estimator's mapped back from its blind copies' placements, and scored against its truth.
    """
    input:
        estimates=lambda w: estimates_files(w.study),
        datasets=lambda w: [
            dataset_file(w.study, c) for c in jb_config.conditions(config, w.study)
        ],
        # An external estimator answers in its blind copies' frames: mapped back with these.
        placements=lambda w: placements_files(
            w.study, jb_config.estimator_names(config, w.study)
        ),
        # Held to what was written from the datasets: an external program may rewrite its own.
        blinds=lambda w: blind_files(
            w.study, jb_config.estimator_names(config, w.study)
        ),
    output:
        "results/collected/{study}.parquet",
    log:
        "results/logs/collect/{study}.log",
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("collect"),
        settings=lambda w: study_settings(
            w.study, "trials", "estimators", "external_estimators"
        ),
    message:
        "collect {wildcards.study}: every estimator's estimates, scored"
    script:
        "../scripts/collect.py"
