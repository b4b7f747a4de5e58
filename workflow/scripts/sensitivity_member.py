from jointbench import jobs
from jointbench.ensembles.sensitivity import write_member

with jobs.job(snakemake):
    # A named member reads its config overlay; a default or drawn member reads none.
    overlay = snakemake.input.overlay
    write_member(
        snakemake.config,
        snakemake.params.study,
        snakemake.wildcards.member,
        [overlay] if isinstance(overlay, str) else list(overlay),
        snakemake.output,
    )
