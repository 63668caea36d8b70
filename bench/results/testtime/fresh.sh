#!/bin/bash
# fresh.sh TAR REPO OUT — the README's two commands on a fresh machine, timed (issue 49).
# TAR: a Debian 12 root file system as a new machine of this project has it (made once with
#   debootstrap --variant=minbase bookworm DIR, then apt-get install --no-install-recommends
#   build-essential cmake ninja-build pkg-config libgtest-dev libgmock-dev libbenchmark-dev
#   clang-format git python3 python3-venv procps ca-certificates; apt-get clean; tar -C DIR -cf TAR .)
# REPO: a git repository whose main is cloned inside. OUT: where the logs go.
# Extracts TAR into a scratch folder, mounts /proc, /sys, /dev, /dev/pts and a /dev/shm tmpfs, clones
# REPO, then runs `bench/run.sh` and `tests/run.sh` in the clone as root, each under `time`;
# the two logs (with tests/run.sh's own time by part) go to OUT (FRESH_COMMANDS: another list). Needs root; nothing else should
# run on the machine meanwhile.
set -eu
TAR=$1 REPO=$2 OUT=$3
mkdir -p "$OUT"
root=$(mktemp -d /work/fresh-XXXX)
cleanup() {
  for m in dev/shm dev/pts dev sys proc; do umount -l "$root/$m" 2>/dev/null || true; done
}
trap cleanup EXIT
tar -C "$root" -xf "$TAR"
mount -t proc proc "$root/proc"
mount --rbind /sys "$root/sys"  # hwloc: without it Open MPI sees no topology, and its ranks sleep
mount --bind /dev "$root/dev"
mount --bind /dev/pts "$root/dev/pts"
mount -t tmpfs -o size=4g tmpfs "$root/dev/shm"
cp /etc/resolv.conf "$root/etc/resolv.conf"
# the host name as the machine resolves it: without it every mpirun waits ~5 s on DNS
cp /etc/hosts "$root/etc/hosts"
cp /etc/hostname "$root/etc/hostname" 2>/dev/null || true
git clone -q --branch main "$REPO" "$root/coloc"
git -C "$root/coloc" log --oneline -1 > "$OUT/commit.txt"
status=0
for cmd in ${FRESH_COMMANDS:-bench/run.sh tests/run.sh}; do
  name=$(basename "$(dirname "$cmd")")
  start=$(date +%s)
  chroot "$root" /bin/bash -c "cd /coloc && export HOME=/root && time $cmd" > "$OUT/$name.log" 2>&1 ||
    { echo "fresh.sh: $cmd failed (exit $?), see $OUT/$name.log"; status=1; }
  echo "$cmd: $(( $(date +%s) - start )) s" | tee -a "$OUT/times.txt"
done
exit $status
