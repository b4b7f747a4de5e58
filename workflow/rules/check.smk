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
        html="results/tables/published_comparison.html",
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
        # The comparison's note names the number of seeds the verdicts are judged over.
        verdict_seeds=jb_config.verdict_seeds(config),
    message:
        "check: every published value and claim against this run"
    script:
        "../scripts/check_published.py"


# For `snakemake --report`: what each output shows and its headline agreement (its caption), a
# page showing it beside its caption, and the report's landing page.
rule report_captions:
    input:
        unpack(lambda w: summarised_tables()),
        unpack(lambda w: {f"shown__{name}": path for name, path, *_ in REPORT_ENTRIES}),
        collected=expand("results/collected/{study}.parquet", study=STUDIES),
    output:
        captions=[CAPTIONS.format(name=name) for name in caption_names()],
        pages=[
            reported(PAGE.format(name=name), name, group, subgroup)
            for name, _, group, subgroup in REPORT_ENTRIES
        ],
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
    message:
        f"report: captions, {len(REPORT_ENTRIES)} pages and the landing page"
    script:
        "../scripts/report_captions.py"
