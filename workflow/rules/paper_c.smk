rule paper_c_table1:
    """Paper C Table 1: sqrt(tr Wc) and v per Nt, published beside ours."""
    input:
        collected="results/collected/hip.parquet",
        published="config/published/paper_c.yaml",
    output:
        csv=reported("results/tables/paper_c_table1.csv", "paper_c_table1"),
        md="results/tables/paper_c_table1.md",
    script:
        "../scripts/paper_c.py"


rule paper_c_calibration:
    """Coverage of the predicted 95 % ellipsoid per Nt (true centre)."""
    input:
        collected="results/collected/hip.parquet",
        published="config/published/paper_c.yaml",
    output:
        csv=reported("results/tables/paper_c_calibration.csv", "paper_c_calibration"),
        md="results/tables/paper_c_calibration.md",
    script:
        "../scripts/paper_c.py"


rule paper_c_uncertainty:
    """Predicted sqrt(tr Wc) vs actual RMS error against Nt, log–log, and coverage."""
    input:
        collected="results/collected/hip.parquet",
        published="config/published/paper_c.yaml",
    output:
        png=reported("results/figures/paper_c_uncertainty.png", "paper_c_uncertainty"),
        pdf="results/figures/paper_c_uncertainty.pdf",
    script:
        "../scripts/paper_c.py"


rule paper_c_claims:
    """Paper C claims C1–C3, each recomputed from our results."""
    input:
        collected="results/collected/hip.parquet",
        published="config/published/paper_c.yaml",
    output:
        csv=reported("results/tables/paper_c_claims.csv", "paper_c_claims"),
        md="results/tables/paper_c_claims.md",
    script:
        "../scripts/paper_c.py"
