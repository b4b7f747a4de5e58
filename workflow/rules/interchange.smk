# What an estimator outside the package is given (README, "Adding an estimator"): a
# condition's blind dataset file, its markers, each trial placed anew in the lab, and grid
# values without the truth (jointbench.resultfiles.parquet.write_blind_dataset; the placements
# go to results/placements/, which collect maps the estimator's answers back with); the same
# markers as CSV for a program to read (jointbench.resultfiles.interchange); and the estimates
# CSV it writes turned into an estimates file. The full dataset, truth and all, is read by the
# built-in estimate jobs and by the benchmark's scoring only. Each rule serves every study, and
# runs only for a file some rule asks for.


rule blind_dataset:
    input:
        "results/datasets/{study}/{condition}.parquet",
    output:
        blind=BLIND,
        # Kept apart from the copy: only the package's rules read it (_check_blind).
        placements=PLACEMENTS,
    log:
        "results/logs/blind/{study}/{condition}.log",
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("blind_dataset"),
        settings={
            "base_seed": config["base_seed"],
            "blind_placement": config["blind_placement"],
        },
    script:
        "../scripts/blind_dataset.py"


rule dataset_csv:
    input:
        rules.blind_dataset.output.blind,
    output:
        "results/interchange/{study}/{condition}.csv",
    log:
        "results/logs/interchange/{study}/{condition}.log",
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("dataset_csv"),
    script:
        "../scripts/dataset_csv.py"


rule estimates_from_csv:
    input:
        estimates="results/estimates/{study}/{method}/{condition}.csv",
        dataset=rules.blind_dataset.output.blind,
        # The markers the program was given, checked whole before its estimates are used.
        markers=rules.dataset_csv.output[0],
    output:
        "results/estimates/{study}/{method}/{condition}.parquet",
    log:
        "results/logs/interchange/{study}/{method}/{condition}.log",
    wildcard_constraints:
        method=_alternatives(EXTERNAL_ESTIMATORS),
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("estimates_from_csv"),
    script:
        "../scripts/estimates_from_csv.py"
