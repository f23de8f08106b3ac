"""Campaigns: many cases of scenarios (a matrix of `--set` values × seeds) run at once on a Dask cluster."""
