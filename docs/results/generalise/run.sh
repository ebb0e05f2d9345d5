#!/usr/bin/env bash
# Issue 80's screen: today's default (pushes cut at the edge) against a quarter of its training
# drops packed arrangements of the family's training types; 2 seeds no claim used, validation only.
cd /work/tree-sealed  # a worktree at 395c698
export PYTHONPATH=/work/tree-sealed PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
python experiments/recipe_study.py --workdir /work/study-80 --variants cut_default family_packed \
  --seeds 20 21 --runs 3 --suites docs/results/validation/val-packed \
  docs/results/validation/val-heaps docs/results/validation/val-occluded-high
