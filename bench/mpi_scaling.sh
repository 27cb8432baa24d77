#!/bin/bash
# 1 vs 2 ranks and plain eval vs mpirun -np 1, alternated, on the drawer's test split with the expert
MB=${MANIBENCH:-$(cd "$(dirname "$0")/.." && pwd)/build/bin/manibench}
A="OpenCabinetDrawer-v0 --policy open_cabinet_expert --controller mobile_panda_ee --split test --episodes-per-object 5 --no-progress"
M="mpirun --allow-run-as-root --oversubscribe"
work=$(mktemp -d) && cd "$work"
t() { local name=$1; shift; /usr/bin/time -f "$name %e s wall %U+%S s cpu" "$@" > /dev/null 2> err.txt; tail -n 1 err.txt; }
for r in 1 2 3; do
  echo "load $(cut -d' ' -f1 /proc/loadavg)"
  t "rank1_$r" $M -np 1 $MB eval $A --out r1_$r
  t "rank2_$r" $M -np 2 $MB eval $A --out r2_$r
  t "plain_$r" $MB eval $A --out p_$r
done
for r in 1 2 3; do cmp r1_$r/episodes.csv r2_$r/episodes.csv && cmp r1_$r/episodes.csv p_$r/episodes.csv && echo "same files $r"; done
