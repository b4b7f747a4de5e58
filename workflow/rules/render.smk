# One job per study renders, from its collected results, everything shown of it: every output of
# its papers this run can render (figures, tables, claims; derived from the paper registry,
# jointbench.papers) and its extended ranking of every estimator. The job reads its inputs once
# and pays for matplotlib once.
for _study in STUDIES:

    rule:
        name:
            f"render_{_study}"
        input:
            collected=f"results/collected/{_study}.parquet",
            published=published_files([_study]),
            datasets=render_datasets(_study),
        output:
            **render_files(_study),
        log:
            f"results/logs/render/{_study}.log",
        conda:
            "../envs/jointbench.yaml"
        params:
            study=_study,
            papers={
                paper.key: [o.name for o in outputs]
                for paper, outputs in papers_to_render(_study)
            },
            code=script_code("render"),
            settings=study_settings(_study, *config["studies"][_study]),
        message:
            f"render {_study}: {len(PAPER_OUTPUTS[_study])} paper outputs and the ranking"
        script:
            "../scripts/render.py"
