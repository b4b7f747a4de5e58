# LM, an estimator outside the jointbench package: the worked example of "Adding an estimator"
# (README). Listed under studies.cmc.external_estimators, its estimates join the collected
# results, the extended ranking and the per-estimator summaries like any built-in's.


rule estimate_cmc_LM:
    """LM: paper A's geometric sphere fit (f1) by Levenberg–Marquardt from the LS centre, one
    condition at a time (workflow/external/lm_sphere.py)."""
    input:
        "results/datasets/cmc/{condition}.parquet",
    output:
        "results/estimates/cmc/LM/{condition}.parquet",
    log:
        "results/logs/estimate/cmc/LM/{condition}.log",
    params:
        # From the Snakefile's folder, so that `snakemake --directory elsewhere` finds it too.
        script=Path(workflow.basedir, "workflow", "external", "lm_sphere.py"),
    shell:
        "{PYTHON:q} {params.script:q} {input:q} {output:q} 2> {log:q}"
