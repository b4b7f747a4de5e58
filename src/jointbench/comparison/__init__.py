"""Comparison with the papers: published values and claims beside ours, the typed tolerances
that judge them, and the regression snapshot of the tabulated means."""
