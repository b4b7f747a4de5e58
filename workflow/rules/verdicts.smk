# Seed ensembles: `snakemake -j2 verdicts` judges every published value and claim in K members,
# each the papers' whole study grids from its own base seed (member 0 is the run's base_seed),
# and tabulates per value and claim the share of seeds in which it reproduces
# (jointbench.ensembles.members). K is `verdicts: {seeds: K}` in the config.
VERDICT_SEEDS = jb_config.verdict_seeds(config)
VERDICT_STUDIES = [study for study in STUDIES if papers_of_study(study)]
MEMBER = "results/verdicts/{study}/member-{member}.csv"


for _study in VERDICT_STUDIES:

    rule:
        name:
            f"verdicts_member_{_study}"
        input:
            published=published_files([_study]),
        output:
            MEMBER.replace("{study}", _study),
        log:
            f"results/logs/verdicts/{_study}/member-{{member}}.log",
        wildcard_constraints:
            member=r"\d+",
        conda:
            "../envs/jointbench.yaml"
        params:
            study=_study,
            code=script_code("verdicts_member"),
            # Every study's settings: a paper's measure may read another study's protocol.
            settings=lambda w: {
                "base_seed": config.get("base_seed"),
                "member": int(w.member),
                "studies": config["studies"],
            },
        script:
            "../scripts/verdicts_member.py"


rule verdicts_summary:
    input:
        members=expand(MEMBER, study=VERDICT_STUDIES, member=range(VERDICT_SEEDS)),
        published=published_files(VERDICT_STUDIES),
    output:
        csv="results/tables/verdicts.csv",
        md="results/tables/verdicts.md",
        html="results/tables/verdicts.html",
    log:
        "results/logs/verdicts_summary.log",
    localrule: True
    conda:
        "../envs/jointbench.yaml"
    params:
        code=script_code("verdicts_summary"),
        settings={"seeds": VERDICT_SEEDS, "base_seed": config.get("base_seed")},
    script:
        "../scripts/verdicts_summary.py"


rule verdicts:
    input:
        rules.verdicts_summary.output,
