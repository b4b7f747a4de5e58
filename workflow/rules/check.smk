rule check_published:
    """Every published value and claim beside ours; fails on a deviation with no recorded reason."""
    input:
        unpack(lambda w: published_tables()),
    output:
        csv=reported("results/tables/published_comparison.csv", "published_comparison"),
        md="results/tables/published_comparison.md",
    script:
        "../scripts/check_published.py"


rule report_captions:
    """Captions for `snakemake --report`: what each output shows, and its headline agreement."""
    input:
        unpack(lambda w: {**published_tables(), **caption_tables()}),
        descriptions="workflow/report/captions.yaml",
    output:
        [CAPTIONS.format(name=name) for name in caption_names()],
    script:
        "../scripts/report_captions.py"
