"""Seed ensembles: a study run over independent base seeds (the members) and the verdict over
them per published value and claim."""
