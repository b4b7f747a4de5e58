# LM, an estimator outside the jointbench package: the worked example of "Adding an estimator"
# (README). Listed under studies.cmc.external_estimators, its estimates join the collected
# results, the extended ranking and the per-estimator summaries like any built-in's.


rule estimate_cmc_LM:
    """LM: paper A's geometric sphere fit (f1) by Levenberg–Marquardt from the LS centre, every
    condition of the study in one job (workflow/external/lm_sphere.py)."""
    input:
        # The program is an input: editing it reruns this job (Snakemake tracks a rule's own
        # code, not the programs its shell command runs).
        script=Path(workflow.basedir, "workflow", "external", "lm_sphere.py"),
        datasets=expand(
            "results/datasets/cmc/{condition}.parquet", condition=condition_ids("cmc")
        ),
    output:
        expand(
            "results/estimates/cmc/LM/{condition}.parquet",
            condition=condition_ids("cmc"),
        ),
    log:
        "results/logs/estimate/cmc/LM.log",
    conda:
        "../../envs/jointbench.yaml"
    params:
        out_dir=lambda w, output: Path(output[0]).parent,
        # The interpreter running this workflow: the project's environment.
        python=PYTHON,
    message:
        f"estimate cmc: LM (external) on {len(condition_ids('cmc'))} conditions"
    shell:
        "{params.python:q} {input.script:q} --out-dir {params.out_dir:q} {input.datasets:q} 2> {log:q}"
