# The extended ranking: every estimator of a study, the paper's and any added (built-in or
# external), ranked by mean error on each condition, as a table and a figure from one job.
for _study in STUDIES:

    rule:
        name:
            f"extended_{_study}"
        input:
            f"results/collected/{_study}.parquet",
        output:
            html=reported(
                f"results/tables/extended_{_study}.html",
                f"extended_{_study}",
                "Extended ranking of every estimator",
                _study,
            ),
            csv=f"results/tables/extended_{_study}.csv",
            md=f"results/tables/extended_{_study}.md",
            png=reported(
                f"results/figures/extended_{_study}.png",
                f"extended_{_study}_figure",
                "Extended ranking of every estimator",
                _study,
            ),
            pdf=f"results/figures/extended_{_study}.pdf",
        log:
            f"results/logs/extended_{_study}.log",
        conda:
            "../envs/jointbench.yaml"
        params:
            study=_study,
            code=code_fingerprint(pipeline.render_extended),
        script:
            "../scripts/extended.py"
