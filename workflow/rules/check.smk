rule check_published:
    input:
        unpack(
            lambda w: {
                study: f"results/collected/{study}.parquet"
                for study in STUDIES
                if papers_of_study(study)
            }
        ),
    output:
        html=reported(
            "results/tables/published_comparison.html",
            "published_comparison",
            "Agreement with the papers",
            "Every value and claim",
        ),
        csv="results/tables/published_comparison.csv",
        md="results/tables/published_comparison.md",
    log:
        "results/logs/check_published.log",
    """Every published value and claim beside ours; fails on a deviation with no recorded reason."""

    # Small: on a cluster it runs on the submitting host rather than waiting in the queue.
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=check_code(),
    script:
        "../scripts/check_published.py"


rule report_captions:
    input:
        unpack(lambda w: summarised_tables()),
        collected=expand("results/collected/{study}.parquet", study=STUDIES),
    output:
        captions=[CAPTIONS.format(name=name) for name in caption_names()],
        front=FRONT_PAGE,
    log:
        "results/logs/report_captions.log",
    """Captions for `snakemake --report`: what each output shows, and its headline agreement."""
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=code_fingerprint(pipeline.write_captions, pipeline.write_front_page),
    script:
        "../scripts/report_captions.py"
