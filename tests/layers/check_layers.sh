#!/bin/bash
# check_layers.sh CXX RSP_DIR PROBES: for each probe line "<layer> <header>
# <ok|missing>", compiles `#include <header>` with the layer's include path
# (RSP_DIR/<layer>.rsp) and checks the outcome: ok must compile, missing
# must fail because the header is not found (not for another reason).
set -u
cxx=$1 dir=$2 probes=$3
failed=0 count=0
while read -r layer header expect; do
  [ -z "$layer" ] && continue
  count=$((count + 1))
  out=$(printf '#include <%s>\nint main() { return 0; }\n' "$header" |
        "$cxx" -std=c++17 -fsyntax-only "@$dir/$layer.rsp" -x c++ - 2>&1)
  status=$?
  if [ "$expect" = ok ]; then
    if [ $status -ne 0 ]; then
      echo "FAIL: layer $layer cannot include its own $header:"; echo "$out" | head -5; failed=1
    fi
  elif [ $status -eq 0 ]; then
    echo "FAIL: layer $layer can include $header, a header of a layer above it"; failed=1
  elif ! grep -q "$header: No such file or directory" <<< "$out"; then
    echo "FAIL: layer $layer including $header failed for another reason:"; echo "$out" | head -5; failed=1
  else
    echo "ok: layer $layer does not see $header"
  fi
done < "$probes"
[ $count -gt 0 ] || { echo "FAIL: no probes in $probes"; exit 1; }
exit $failed
