#!/usr/bin/env bash
# The 5-seed reproduction of issue 52 (each method on the preset the screen chose, RECIPES), from a
# worktree at its commit: the frozen protocol first (its tables land on their own), then both;
# a crashed invocation (killed by a signal: an LLVM allocation failure once killed a long online
# evaluation) is started again, keeping what finished. Resumable: run this again after a stop.
cd /work/repro-tree
export PYTHONPATH=/work/repro-tree PATH=/work/main/.venv/bin:$PATH
log=/work/reproduction5/runs.txt
for protocols in frozen "frozen online"; do
  for try in 1 2 3 4 5 6 7 8; do
    echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD) protocols $protocols" >> $log
    mvcoba-reproduce --workdir /work/reproduction5/runs --out /work/reproduction5/tables \
      --protocols $protocols >> /work/reproduction5/reproduce.log 2>&1
    rc=$?  # before the date's command substitution resets it
    echo "end $(date -u +%FT%TZ) rc $rc" >> $log
    [ $rc -eq 0 ] && break
    [ $rc -lt 128 ] && exit $rc  # refused or failed: not a crash, do not start again
  done
done
