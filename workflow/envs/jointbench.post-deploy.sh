#!/usr/bin/env bash
# Snakemake runs this inside the new conda environment, from its working directory: install
# jointbench from the work tree, editable, so that the jobs run the code that is checked out.
set -euo pipefail
if ! grep -qs '^name = "jointbench"' pyproject.toml; then
    echo "jointbench.post-deploy.sh: $PWD is not a jointbench work tree (no pyproject.toml" \
        "naming jointbench); create the conda environment by running snakemake from the work" \
        "tree, or install jointbench into it by hand" >&2
    exit 1
fi
python -m pip install --quiet --no-deps --no-build-isolation --editable .
