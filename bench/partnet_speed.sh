#!/usr/bin/env bash
# Env steps per second on real PartNet-Mobility objects beside ManiSkill's
# Table 4 (supplement B.1, measured on real objects): every task on the
# folder's objects of its category, state (the random policy and the
# task's expert) and pointcloud (the random policy: the experts read the
# privileged state), RUNS runs each (median), and the cost of loading
# the objects (manibench objects --check: the first scene build and again).
#
#   bench/partnet_speed.sh PARTNET_DIR [BUILD_DIR] [RUNS]
#
# PARTNET_DIR holds the category folders (StorageFurniture, Chair, Bucket),
# as ../shared/partnet does. Prints a Markdown table (docs/partnet.md).
set -euo pipefail
partnet=${1:?usage: bench/partnet_speed.sh PARTNET_DIR [BUILD_DIR] [RUNS]}
build=${2:-build}
runs=${3:-3}
cli=$build/bin/manibench

# task, category, expert, Table 4's state and pointcloud figures
tasks=(
  "OpenCabinetDrawer-v0 StorageFurniture open_cabinet_expert 113±4 47±2"
  "OpenCabinetDoor-v0 StorageFurniture open_cabinet_expert 112±4 48±3"
  "PushChair-v0 Chair push_chair_expert 53±9 31±4"
  "MoveBucket-v0 Bucket move_bucket_expert 61±7 34±3"
)

# The median of the numbers on standard input.
median() { sort -n | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }

echo "| task | mode | policy | env steps/s (median of $runs) | runs | ManiSkill Table 4 |"
echo "|---|---|---|---|---|---|"
for entry in "${tasks[@]}"; do
  read -r task category expert table_state table_cloud <<<"$entry"
  for mode in state pointcloud; do
    steps=2000
    [ "$mode" = pointcloud ] && steps=400
    policies=(random "$expert")
    # The experts read the privileged state: pointcloud runs the random policy.
    [ "$mode" = pointcloud ] && policies=(random)
    for policy in "${policies[@]}"; do
      controller=()
      [ "$policy" != random ] && controller=(--controller mobile_panda_ee)
      rates=()
      for ((r = 0; r < runs; ++r)); do
        rates+=("$("$cli" bench "$task" --obs "$mode" --policy "$policy" "${controller[@]}" --steps "$steps" \
          --set "task.partnet_dir=$partnet/$category" 2>/dev/null |
          sed -n 's/.*, \([0-9.]*\) env steps\/s.*/\1/p')")
      done
      table=$table_state
      [ "$mode" = pointcloud ] && table=$table_cloud
      echo "| $task | $mode | $policy | **$(printf '%s\n' "${rates[@]}" | median)** | ${rates[*]} | $table |"
    done
  done
done

echo
echo "Loading (manibench objects --check: scene built the first time, and again from the mesh caches):"
for entry in "${tasks[@]}"; do
  read -r task category _ <<<"$entry"
  echo
  echo "$task ($category):"
  "$cli" objects "$task" --check --set "task.partnet_dir=$partnet/$category" 2>/dev/null | sed -n 's/^  /    /p'
done
