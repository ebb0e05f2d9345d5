#!/usr/bin/env bash
# Issue 81: the shipped default (pretrained/mvcoba) on the held-out everyday objects as it is,
# 5 runs per case, frozen, cap 60; and on val-novel (the procedural validation twin), 3 runs.
cd /work/tree-objects && export PYTHONPATH=/work/tree-objects PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
w=/work/objects
echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> $w/runs.txt
mvcoba-eval --checkpoint pretrained/mvcoba --suite novel --runs 5 --out $w/shipped-novel --resume \
  > $w/shipped-novel.log 2>&1; echo "novel rc $? $(date -u +%FT%TZ)" >> $w/runs.txt
mvcoba-eval --checkpoint pretrained/mvcoba --suite docs/results/validation/val-novel --runs 3 \
  --out $w/shipped-val-novel --resume > $w/shipped-val-novel.log 2>&1
echo "val-novel rc $? $(date -u +%FT%TZ)" >> $w/runs.txt
