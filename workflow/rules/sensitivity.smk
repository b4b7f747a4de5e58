# Protocol ensembles: `snakemake -j2 sensitivity` judges every published value and claim of the
# studies with a prior over their unpublished choices (jointbench.ensembles.sensitivity) in the
# default protocol, in N protocols drawn from the prior (`sensitivity: {draws: N}`) and in each
# named protocol (`sensitivity: {named: {name: overlay}}`), every one from the run's base seed.
from jointbench.figures.sensitivity import FIGURES as SENSITIVITY_FIGURES
from jointbench.ensembles.named import DEFAULT, DRAW_PREFIX, ensembles

SENSITIVITY = config.get("sensitivity", {})
SENSITIVITY_NAMED = dict(SENSITIVITY.get("named", {}))
# Each named protocol's config overlay, read and checked once for all the studies with an
# ensemble, and only where one has, and the members of each study's ensemble, as `jointbench
# fit --configfile` reads them; a mistake names the config file that set it.
SENSITIVITY_OVERLAYS, SENSITIVITY_MEMBERS = ensembles(config, CONFIG_SOURCES)
SENSITIVITY_STUDIES = list(SENSITIVITY_MEMBERS)
SENSITIVITY_FILES = {
    kind: [
        f"results/sensitivity/{study}/{member}{suffix}.csv"
        for study in SENSITIVITY_STUDIES
        for member in SENSITIVITY_MEMBERS[study]
    ]
    for kind, suffix in (("rows", ""), ("values", "-values"), ("curve", "-curve"))
}


for _study in SENSITIVITY_STUDIES:

    rule:
        name:
            f"sensitivity_member_{_study}"
        input:
            published=published_files([_study]),
            overlay=lambda w: (
                [SENSITIVITY_NAMED[w.member]] if w.member in SENSITIVITY_NAMED else []
            ),
        output:
            rows=f"results/sensitivity/{_study}/{{member}}.csv",
            values=f"results/sensitivity/{_study}/{{member}}-values.csv",
            curve=f"results/sensitivity/{_study}/{{member}}-curve.csv",
        log:
            f"results/logs/sensitivity/{_study}/{{member}}.log",
        # Each member's wall and CPU time: what the target's duration is made of.
        benchmark:
            f"results/benchmarks/sensitivity/{_study}/{{member}}.tsv"
        wildcard_constraints:
            member=_alternatives([DEFAULT, *SENSITIVITY_NAMED]) + rf"|{DRAW_PREFIX}\d+",
        conda:
            "../envs/jointbench.yaml"
        params:
            study=_study,
            code=script_code("sensitivity_member"),
            # Every study's settings: a paper's measure may read another study's protocol.
            settings=lambda w: {
                "base_seed": config.get("base_seed"),
                "member": w.member,
                "studies": config["studies"],
            },
        script:
            "../scripts/sensitivity_member.py"


rule sensitivity_summary:
    input:
        rows=SENSITIVITY_FILES["rows"],
        values=SENSITIVITY_FILES["values"],
        published=published_files(SENSITIVITY_STUDIES),
    output:
        csv="results/tables/sensitivity.csv",
        md="results/tables/sensitivity.md",
        html="results/tables/sensitivity.html",
        named_csv="results/tables/sensitivity_named.csv",
        named_md="results/tables/sensitivity_named.md",
        named_html="results/tables/sensitivity_named.html",
        prior_csv="results/tables/sensitivity_prior.csv",
        prior_md="results/tables/sensitivity_prior.md",
        prior_html="results/tables/sensitivity_prior.html",
    log:
        "results/logs/sensitivity_summary.log",
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("sensitivity_summary"),
        settings={"members": SENSITIVITY_MEMBERS, "base_seed": config.get("base_seed")},
    script:
        "../scripts/sensitivity_summary.py"


rule sensitivity_figures:
    input:
        rows=SENSITIVITY_FILES["rows"],
        curves=SENSITIVITY_FILES["curve"],
    output:
        **{
            f"{SENSITIVITY_FIGURES[s]}_{kind}": (
                f"results/figures/sensitivity_{SENSITIVITY_FIGURES[s]}.{kind}"
            )
            for s in SENSITIVITY_STUDIES
            if s in SENSITIVITY_FIGURES
            for kind in ("png", "pdf")
        },
    log:
        "results/logs/sensitivity_figures.log",
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("sensitivity_figures"),
        settings={"members": SENSITIVITY_MEMBERS, "named": SENSITIVITY_NAMED},
    script:
        "../scripts/sensitivity_figures.py"


rule sensitivity:
    input:
        rules.sensitivity_summary.output,
        rules.sensitivity_figures.output,
