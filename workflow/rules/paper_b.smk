rule paper_b_table1:
    """Paper B Table 1: every cell, published mean beside ours, within tolerance or not."""
    input:
        collected="results/collected/hinge.parquet",
        published="config/published/paper_b.yaml",
    output:
        csv=reported("results/tables/paper_b_table1.csv", "paper_b_table1"),
        md="results/tables/paper_b_table1.md",
    script:
        "../scripts/paper_b.py"


rule paper_b_fig5:
    """Paper B Fig 5: mean AoR error with min–max bars, (a) knee, (b) index MCP."""
    input:
        collected="results/collected/hinge.parquet",
    output:
        png=reported("results/figures/paper_b_fig5.png", "paper_b_fig5"),
        pdf="results/figures/paper_b_fig5.pdf",
    script:
        "../scripts/paper_b.py"


rule paper_b_fig2:
    """Paper B Fig 2: best-fitting plane, cylinder and circle on two trials with a known axis."""
    output:
        png=reported("results/figures/paper_b_fig2.png", "paper_b_fig2"),
        pdf="results/figures/paper_b_fig2.pdf",
    script:
        "../scripts/paper_b.py"


rule paper_b_claims:
    """Paper B claims B1–B6, each recomputed from our results."""
    input:
        collected="results/collected/hinge.parquet",
        published="config/published/paper_b.yaml",
    output:
        csv=reported("results/tables/paper_b_claims.csv", "paper_b_claims"),
        md="results/tables/paper_b_claims.md",
    script:
        "../scripts/paper_b.py"
