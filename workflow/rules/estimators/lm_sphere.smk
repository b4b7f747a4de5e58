# LM, an estimator outside the jointbench package: the worked example of "Adding an estimator"
# (README). Listed under a study's external_estimators (the cmc study's by default), its
# estimates join the collected results, the extended ranking and the per-estimator summaries
# like any built-in's. One rule per study that lists it; a study not in the run has none.
# Its estimates are a centre's: only a study of centre estimates may list it.
external_estimator("LM", kind="center")

for _study in studies_listing("LM"):

    rule:
        name:
            f"estimate_{_study}_LM"
        input:
            # The program is an input: editing it reruns the job (Snakemake tracks a rule's
            # own code, not the programs its shell command runs).
            script=Path(workflow.basedir, "workflow", "external", "lm_sphere.py"),
            datasets=expand(
                "results/blind/{study}/{condition}.parquet",
                study=_study,
                condition=condition_ids(_study),
            ),
        output:
            expand(
                "results/estimates/{study}/LM/{condition}.parquet",
                study=_study,
                condition=condition_ids(_study),
            ),
        log:
            f"results/logs/estimate/{_study}/LM/LM.log",
        conda:
            "../../envs/jointbench.yaml"
        params:
            out_dir=lambda w, output: Path(output[0]).parent,
            # The interpreter running this workflow: the project's environment.
            python=PYTHON,
        message:
            f"estimate {_study}: LM (external) on {len(condition_ids(_study))} conditions"
        shell:
            "{params.python:q} {input.script:q} --out-dir {params.out_dir:q} {input.datasets:q} 2> {log:q}"
