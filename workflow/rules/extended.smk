# The extended ranking: every estimator of a study, the paper's and any added (built-in or
# external), ranked by mean error on each condition. One rule per study and output, so that
# every report caption is a concrete file.
for _study in STUDIES:

    rule:
        name:
            f"extended_table_{_study}"
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
        log:
            f"results/logs/extended_table_{_study}.log",
        # Small: on a cluster it runs on the submitting host rather than waiting in the queue.
        localrule: True
        conda:
            "../envs/jointbench.yaml"
        params:
            study=_study,
            what="table",
            code=code_fingerprint(pipeline.render_extended),
        script:
            "../scripts/extended.py"

    rule:
        name:
            f"extended_figure_{_study}"
        input:
            f"results/collected/{_study}.parquet",
        output:
            png=reported(
                f"results/figures/extended_{_study}.png",
                f"extended_{_study}_figure",
                "Extended ranking of every estimator",
                _study,
            ),
            pdf=f"results/figures/extended_{_study}.pdf",
        log:
            f"results/logs/extended_figure_{_study}.log",
        conda:
            "../envs/jointbench.yaml"
        params:
            study=_study,
            what="figure",
            code=code_fingerprint(pipeline.render_extended),
        script:
            "../scripts/extended.py"
