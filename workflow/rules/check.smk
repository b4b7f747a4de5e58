# Every published value and claim beside ours; fails on a deviation with no recorded reason.
# Small rules like this one run on the submitting host of a cluster (localrule).
rule check_published:
    input:
        unpack(
            lambda w: {
                study: f"results/collected/{study}.parquet"
                for study in STUDIES
                if papers_of_study(study)
            }
        ),
        published=published_files(STUDIES),
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
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("check_published"),
        settings={study: config["studies"][study] for study in STUDIES},
        base_seed=config.get("base_seed"),
    script:
        "../scripts/check_published.py"


# Captions for `snakemake --report`: what each output shows, its headline agreement, and the
# report's landing page.
rule report_captions:
    input:
        unpack(lambda w: summarised_tables()),
        collected=expand("results/collected/{study}.parquet", study=STUDIES),
    output:
        captions=[CAPTIONS.format(name=name) for name in caption_names()],
        front=FRONT_PAGE,
    log:
        "results/logs/report_captions.log",
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("report_captions"),
        settings={study: config["studies"][study] for study in STUDIES},
        base_seed=config.get("base_seed"),
    script:
        "../scripts/report_captions.py"
