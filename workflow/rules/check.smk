rule check_published:
    """Every published value and claim beside ours; fails on a deviation with no recorded reason."""
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
    conda:
        "../envs/jointbench.yaml"
    params:
        code=check_code(),
    script:
        "../scripts/check_published.py"


rule report_captions:
    """Captions for `snakemake --report`: what each output shows, and its headline agreement."""
    input:
        unpack(lambda w: summarised_tables()),
    output:
        captions=[CAPTIONS.format(name=name) for name in caption_names()],
        front=FRONT_PAGE,
    log:
        "results/logs/report_captions.log",
    conda:
        "../envs/jointbench.yaml"
    params:
        code=code_fingerprint(pipeline.write_captions),
    script:
        "../scripts/report_captions.py"
