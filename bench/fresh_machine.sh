#!/usr/bin/env bash
# Times the README's `make demo` on a fresh Debian 12 userland: a debootstrap
# root with nothing but the base system, make and git, on this machine's
# cores, so the apt part is measured too (issue 29's target: 4 min 30 s).
# The clone is from REPO's committed HEAD; ccache is not installed there.
# Needs root and debootstrap (`apt install debootstrap`; a measuring tool,
# not a dependency of the project). The root is kept, packages included:
# delete ROOT before a run for a fresh measurement. With --and-test, then
# times `make test` in the same clone (the README's second command).
#   bench/fresh_machine.sh [--and-test] ROOT [REPO]   (REPO: this checkout)
set -euo pipefail
and_test=0
if [[ ${1:-} == --and-test ]]; then and_test=1; shift; fi
root=${1:?usage: bench/fresh_machine.sh [--and-test] ROOT [REPO]}
repo=$(realpath "${2:-$(dirname "$0")/..}")
mirror=${MIRROR:-http://deb.debian.org/debian}

if [[ ! -f $root/etc/debian_version ]]; then
  echo "debootstrap bookworm into $root (not timed)"
  debootstrap --include=make,git,ca-certificates bookworm "$root" "$mirror" >"$root.debootstrap.log"
fi
cp /etc/resolv.conf "$root/etc/resolv.conf"
rm -rf "$root/root/manibench"
git clone -q --no-local "$repo" "$root/root/manibench"

# A private mount namespace whose root IS the new root (pivot_root, not
# chroot), so that nothing mounted here outlives the run.
unshare --mount --fork bash -euo pipefail -s "$root" "$and_test" <<'EOF'
root=$1 and_test=$2
mount --make-rprivate /
mount --bind "$root" "$root"
mount -t proc proc "$root/proc"
mount --rbind /sys "$root/sys"
mount --rbind /dev "$root/dev"
mount -t tmpfs tmpfs "$root/tmp"
cd "$root"
mkdir -p .old-root
pivot_root . .old-root
umount -l /.old-root
cd /root/manibench
export PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8 DEBIAN_FRONTEND=noninteractive
echo "cores: $(nproc); load before: $(cut -d' ' -f1-3 /proc/loadavg)"
t0=$(date +%s)
scripts/install-deps --demo >/root/install-deps.log 2>&1 || { tail -30 /root/install-deps.log; exit 1; }
t1=$(date +%s)
make demo >/root/make-demo.log 2>&1 || { tail -30 /root/make-demo.log; exit 1; }
t2=$(date +%s)
tail -4 /root/make-demo.log
echo "make demo on a fresh Debian 12 root: $((t2 - t0)) s in all:" \
     "$((t1 - t0)) s of apt (scripts/install-deps --demo, which make demo runs first)," \
     "$((t2 - t1)) s of configure, build and demo"
if ((and_test)); then
  scripts/install-deps >/root/install-deps-test.log 2>&1 || { tail -30 /root/install-deps-test.log; exit 1; }
  t3=$(date +%s)
  make test >/root/make-test.log 2>&1 || { tail -60 /root/make-test.log; exit 1; }
  t4=$(date +%s)
  grep -E "tests passed|Total Test time" /root/make-test.log
  echo "then make test: $((t4 - t2)) s in all: $((t3 - t2)) s of apt (scripts/install-deps)," \
       "$((t4 - t3)) s of configure, build and ctest"
fi
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
EOF
