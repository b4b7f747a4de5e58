"""What a run is: its configuration (loading, checks, the condition grid), the registry of
studies it can run, and the seeds of every trial."""
