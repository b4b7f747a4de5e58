# centroid: the smallest external estimator, a template to copy (README, "Adding an estimator").
# It serves every centre study that lists it under external_estimators, and runs nowhere else.
# Like every external estimator it reads the condition's blind dataset file: the markers and the
# condition's grid values, not the truth, which only the benchmark reads to score.
# It writes a centre's estimates (center_x, center_y, center_z), as it declares: a study of
# another kind that lists it stops the run before any job, naming both kinds.
external_estimator("centroid", kind="center")


rule estimate_centroid:
    """centroid: the mean of every marker position of a trial (a template, not a method)."""
    input:
        "results/blind/{study}/{condition}.parquet",
    output:
        "results/estimates/{study}/centroid/{condition}.parquet",
    log:
        "results/logs/estimate/{study}/centroid/{condition}.log",
    conda:
        "../../envs/jointbench.yaml"
    script:
        "../../external/centroid.py"
