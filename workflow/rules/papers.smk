# One rule per paper output, derived from the paper registry (jointbench.papers): each reads its
# study's collected results, its paper's published values and the datasets it draws.
for _study in STUDIES:
    for _paper, _output in PAPER_OUTPUTS[_study]:
        _files = dict(_output.files)
        _first = next(iter(_files))
        _files[_first] = reported(
            _files[_first],
            _output.name,
            _paper.title,
            "Figures" if _output.kind == "figure" else "Tables",
        )

        rule:
            name:
                _output.name
            input:
                collected=f"results/collected/{_study}.parquet",
                published=str(_paper.published),
                datasets=[dataset_file(_study, c) for c in _output.conditions],
            output:
                **_files,
            log:
                f"results/logs/{_output.name}.log",
            # Tables are small: on a cluster they run on the submitting host.
            localrule: _output.kind == "table"
            conda:
                "../envs/jointbench.yaml"
            params:
                paper=_paper.key,
                output=_output.name,
                code=output_code(_paper, _output),
            script:
                "../scripts/render.py"
