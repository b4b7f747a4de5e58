# One rule per paper, derived from the paper registry (jointbench.papers): it reads its study's
# collected results, its published values and the datasets its outputs draw, and renders every
# output of the paper this run can render (figures, tables, claims) in one job.
for _study in STUDIES:
    for _paper, _outputs in papers_to_render(_study):

        rule:
            name:
                _paper.key
            input:
                collected=f"results/collected/{_study}.parquet",
                published=str(_paper.published),
                datasets=paper_datasets(_study, _outputs),
            output:
                **paper_files(_paper, _outputs),
            log:
                f"results/logs/{_paper.key}.log",
            conda:
                "../envs/jointbench.yaml"
            params:
                paper=_paper.key,
                outputs=[o.name for o in _outputs],
                code=paper_code(_outputs),
            script:
                "../scripts/render.py"
