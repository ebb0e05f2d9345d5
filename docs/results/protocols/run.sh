#!/usr/bin/env bash
set -e
cd /work/main
. .venv/bin/activate
P=/work/study-recipe/paper_text
for proto in frozen online no-repeat; do
  flag=""; [ "$proto" = online ] && flag="--online"; [ "$proto" = no-repeat ] && flag="--no-repeat"
  mvcoba-eval --checkpoint $P/mvcoba-s0 $P/mvcoba-s1 --suite occluded --runs 5 $flag --out /work/protocols/$proto --resume
done
mvcoba-eval --tables /work/protocols/frozen /work/protocols/online /work/protocols/no-repeat --out /work/protocols/joined --overwrite
