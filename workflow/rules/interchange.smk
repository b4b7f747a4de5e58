# Plain text for estimators in any language (jointbench.resultfiles.interchange): a condition's
# markers as CSV for a program to read, and the estimates CSV it writes turned into an estimates
# file.
# Both rules serve every study, and run only for a file some rule asks for.


rule dataset_csv:
    input:
        "results/datasets/{study}/{condition}.parquet",
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
        dataset="results/datasets/{study}/{condition}.parquet",
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
