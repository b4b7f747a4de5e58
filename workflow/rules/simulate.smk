# One job per study writes every condition's dataset file: the simulation of a condition takes
# milliseconds, far less than starting a job.
for _study in STUDIES:

    rule:
        name:
            f"simulate_{_study}"
        output:
            expand(
                "results/datasets/{study}/{condition}.parquet",
                study=_study,
                condition=condition_ids(_study),
            ),
        log:
            f"results/logs/simulate/{_study}.log",
        conda:
            "../envs/jointbench.yaml"
        params:
            study=_study,
            code=script_code("simulate"),
            settings=study_settings(_study, "grid", *SIMULATION_KEYS),
        message:
            f"simulate {_study}: {len(condition_ids(_study))} conditions"
        script:
            "../scripts/simulate.py"
