# The extended ranking: every estimator of a study, the paper's and any added (built-in or
# external), ranked by mean error on each condition.


rule extended_table:
    """Per condition and method: trials, converged, failed, mean and median error, rank, best."""
    input:
        "results/collected/{study}.parquet",
    output:
        csv=reported("results/tables/extended_{study}.csv", "extended_{study}"),
        md="results/tables/extended_{study}.md",
    script:
        "../scripts/extended.py"


rule extended_figure:
    """Condition × method heat map of mean error, best per condition outlined, and mean ranks."""
    input:
        "results/collected/{study}.parquet",
    output:
        png=reported("results/figures/extended_{study}.png", "extended_{study}_figure"),
        pdf="results/figures/extended_{study}.pdf",
    script:
        "../scripts/extended.py"
