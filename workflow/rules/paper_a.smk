rule paper_a_fig4:
    """Paper A Fig 4: mean CoR error vs RoM per method and noise level, M and H sets."""
    input:
        "results/collected/cmc.parquet",
    output:
        png=reported("results/figures/paper_a_fig4.png", "paper_a_fig4"),
        pdf="results/figures/paper_a_fig4.pdf",
    script:
        "../scripts/paper_a.py"


rule paper_a_fig3:
    """Paper A Fig 3: one ±5°, 1.0 mm M-set trial with every method's estimate."""
    input:
        dataset="results/datasets/cmc/marker_set-M__rom_deg-5__noise_mm-1.0.parquet",
        collected="results/collected/cmc.parquet",
        published="config/published/paper_a.yaml",
    output:
        png=reported("results/figures/paper_a_fig3.png", "paper_a_fig3"),
        pdf="results/figures/paper_a_fig3.pdf",
    script:
        "../scripts/paper_a.py"


rule paper_a_table2:
    """Paper A Table 2: computation time per trial beside the published MATLAB times."""
    input:
        collected="results/collected/cmc.parquet",
        published="config/published/paper_a.yaml",
    output:
        csv=reported("results/tables/paper_a_table2.csv", "paper_a_table2"),
        md="results/tables/paper_a_table2.md",
    script:
        "../scripts/paper_a.py"


rule paper_a_claims:
    """Paper A claims A1–A11, each recomputed from our results."""
    input:
        collected="results/collected/cmc.parquet",
        published="config/published/paper_a.yaml",
    output:
        csv=reported("results/tables/paper_a_claims.csv", "paper_a_claims"),
        md="results/tables/paper_a_claims.md",
    script:
        "../scripts/paper_a.py"
