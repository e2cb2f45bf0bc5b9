#!/usr/bin/env bash
# Builds the Debian package and checks it on a fresh Debian 12: debootstrap a minimal bookworm
# into a temporary folder, install the .deb there with apt (which fetches its dependencies), then
# simulate an office, init a rig config from it, calibrate, run and check the ATE.
# Needs root (debootstrap, chroot) and Debian's mirror; takes a few minutes.
# Usage: scripts/test_deb.sh [ROOT_DIR]   (default: a new temporary folder, removed afterwards)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh >/dev/null
(cd build && cpack -G DEB >/dev/null)
deb=$(ls build/mmlio_*_amd64.deb | tail -1)
command -v debootstrap >/dev/null || apt-get install -y -q debootstrap >/dev/null
given="${1:-}"
root="${given:-$(mktemp -d)}"
cleanup() {
  umount "$root/proc" 2>/dev/null || true
  if [ -z "$given" ]; then rm -rf "$root"; fi  # a folder given is kept for the next run
}
trap cleanup EXIT
[ -x "$root/bin/bash" ] || debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian >/dev/null
cp /etc/resolv.conf "$root/etc/resolv.conf"
mountpoint -q "$root/proc" || mount -t proc proc "$root/proc"
cp "$deb" "$root/tmp/mmlio.deb"
chroot "$root" bash -c 'apt-get update -q >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends /tmp/mmlio.deb >/dev/null'
chroot "$root" bash -ec '
  cd /tmp
  mmlio --version
  mmlio -q simulate --scenario office --duration 15 --out sim >/dev/null 2>&1
  mmlio init sim/office.bag --out rig.yaml --force >/dev/null
  mmlio -q calibrate sim/office.bag --config rig.yaml --out calib.yaml >/dev/null
  mmlio -q run sim/office.bag --config rig.yaml --calib calib.yaml --gt sim/office_gt.tum --out out --no-progress |
    tee run.txt | grep "ATE"
  ate=$(sed -n "s/.*ATE \([0-9.]*\) cm.*/\1/p" run.txt)
  awk -v a="$ate" "BEGIN { exit !(a > 0 && a < 3) }" || { echo "ATE $ate cm: too large"; exit 1; }
  test -x /usr/bin/mmlio_node && test -f /usr/share/mmlio/config/hvi.yaml
'
echo "ok: $deb installs on a fresh Debian 12 and runs"
