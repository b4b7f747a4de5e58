# Protocol ensembles: `snakemake -j2 sensitivity` judges every published value and claim of the
# studies with a prior over their unpublished choices (jointbench.study.sensitivity) in the
# default protocol, in N protocols drawn from the prior (`sensitivity: {draws: N}`) and in each
# named protocol (`sensitivity: {named: {name: overlay}}`), every one from the run's base seed.
import yaml

from jointbench.figures.sensitivity import FIGURES as SENSITIVITY_FIGURES
from jointbench.study.sensitivity import DEFAULT, DRAW_PREFIX, PRIORS

SENSITIVITY = config.get("sensitivity", {})
SENSITIVITY_DRAWS = int(SENSITIVITY.get("draws", 1))
SENSITIVITY_STUDIES = [s for s in STUDIES if s in PRIORS and papers_of_study(s)]
SENSITIVITY_ROWS = "results/sensitivity/{study}/{member}.csv"
SENSITIVITY_VALUES = "results/sensitivity/{study}/{member}-values.csv"
SENSITIVITY_CURVE = "results/sensitivity/{study}/{member}-curve.csv"


def _overlay_studies(path):
    """The studies whose protocol the config overlay at ``path`` sets."""
    document = yaml.safe_load(Path(path).read_text()) or {}
    return [
        s for s, v in document.get("studies", {}).items() if "protocol" in (v or {})
    ]


SENSITIVITY_NAMED = {
    name: path
    for name, path in SENSITIVITY.get("named", {}).items()
    if name != DEFAULT and not name.startswith(DRAW_PREFIX)
}


def sensitivity_members(study):
    """Every member of ``study``'s protocol ensemble: the default, the draws, the named
    protocols that set its protocol."""
    draws = [f"{DRAW_PREFIX}{k}" for k in range(1, SENSITIVITY_DRAWS + 1)]
    named = [n for n, p in SENSITIVITY_NAMED.items() if study in _overlay_studies(p)]
    return [DEFAULT, *draws, *named]


def sensitivity_files(pattern, studies):
    return [
        pattern.format(study=s, member=m)
        for s in studies
        for m in sensitivity_members(s)
    ]


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
            rows=SENSITIVITY_ROWS.replace("{study}", _study),
            values=SENSITIVITY_VALUES.replace("{study}", _study),
            curve=SENSITIVITY_CURVE.replace("{study}", _study),
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
        rows=sensitivity_files(SENSITIVITY_ROWS, SENSITIVITY_STUDIES),
        values=sensitivity_files(SENSITIVITY_VALUES, SENSITIVITY_STUDIES),
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
        settings={"draws": SENSITIVITY_DRAWS, "base_seed": config.get("base_seed")},
    script:
        "../scripts/sensitivity_summary.py"


rule sensitivity_figures:
    input:
        rows=sensitivity_files(SENSITIVITY_ROWS, SENSITIVITY_STUDIES),
        curves=sensitivity_files(SENSITIVITY_CURVE, SENSITIVITY_STUDIES),
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
        settings={"draws": SENSITIVITY_DRAWS, "named": SENSITIVITY_NAMED},
    script:
        "../scripts/sensitivity_figures.py"


rule sensitivity:
    input:
        rules.sensitivity_summary.output,
        rules.sensitivity_figures.output,
