# LS-C: paper A's LS sphere fit as a C program (workflow/external/ls_sphere.c), the worked example
# of an estimator in a compiled language. One rule serves every centre study that lists LS-C
# under external_estimators: it reads the condition's markers as CSV and writes its estimates as
# CSV, which the interchange rules (workflow/rules/interchange.smk) convert; no Python of its own.
# Its estimates are a centre's: only a study of centre estimates may list it.
external_estimator("LS-C", kind="center")


rule compile_ls_sphere:
    input:
        Path(workflow.basedir, "workflow", "external", "ls_sphere.c"),
    output:
        "results/bin/ls_sphere",
    log:
        "results/logs/compile/ls_sphere.log",
    localrule: True
    conda:
        "../../envs/c.yaml"
    params:
        # Another compiler may optimise the program otherwise: it is compiled again.
        compiler=compiler_version("cc"),
    shell:
        "cc -std=c99 -O2 -Wall -Wextra -o {output:q} {input:q} -lm 2> {log:q}"


rule estimate_LS_C:
    input:
        program=rules.compile_ls_sphere.output[0],
        markers="results/interchange/{study}/{condition}.csv",
    output:
        "results/estimates/{study}/LS-C/{condition}.csv",
    log:
        "results/logs/estimate/{study}/LS-C/{condition}.log",
    conda:
        "../../envs/c.yaml"
    shell:
        "{input.program:q} {input.markers:q} > {output:q} 2> {log:q}"
