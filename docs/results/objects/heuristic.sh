#!/usr/bin/env bash
# The scripted heuristic on novel: how much of the shipped policy's figure the objects allow.
while pgrep -f "objects/run.sh" > /dev/null; do sleep 20; done
cd /work/tree-objects && export PYTHONPATH=/work/tree-objects PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
mvcoba-eval --baseline heuristic --suite novel --runs 5 --out /work/objects/heuristic-novel --resume \
  > /work/objects/heuristic-novel.log 2>&1; echo "heuristic novel rc $? $(date -u +%FT%TZ)" >> /work/objects/runs.txt
