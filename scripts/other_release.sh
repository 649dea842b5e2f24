#!/usr/bin/env bash
# Run make targets of this checkout in chroots of other Debian releases: Debian 12 (bookworm, dolfinx 0.5.2),
# Debian 13 (trixie, dolfinx 0.9) and Debian unstable (sid, dolfinx 0.11). Each chroot is made with debootstrap from
# the machine's own Debian mirror and cached under /var/tmp/dolfinx_ntf-<release>, so a second run only pays for the
# tests. Needs root.
#
#   bash scripts/other_release.sh [RELEASE ...] [make target ...]
#
# RELEASE is bookworm, trixie or sid; by default all three but the machine's own (what `make test-all` checks).
# The make targets default to test-here. Every release is run even when one fails; the exit
# status says whether all passed. (`set -e` does not act inside run_release, which runs as an `if` condition: its
# steps say `|| return 1`.)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

if [ "$(id -u)" != 0 ]; then
  command -v sudo >/dev/null || { echo "other_release: needs root or sudo (debootstrap, chroot, mount)" >&2; exit 1; }
  exec sudo --preserve-env=CI bash "$0" "$@"
fi
here=$(sh scripts/debian_release.sh)
default_releases=(bookworm trixie sid)
releases=()
targets=()
for arg in "$@"; do
  case "$arg" in
    bookworm | trixie | sid) releases+=("$arg") ;;
    *) targets+=("$arg") ;;
  esac
done
if [ ${#releases[@]} -eq 0 ]; then
  for r in "${default_releases[@]}"; do [ "$r" = "$here" ] || releases+=("$r"); done
fi
[ ${#targets[@]} -gt 0 ] || targets=(test-here)

mirror=$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)
[ -n "$mirror" ] || mirror=$(awk '/^deb /{print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)
[ -n "$mirror" ] || mirror=http://deb.debian.org/debian

# Make (once) and enter the chroot of release $1, then run the make targets in a fresh copy of this checkout.
run_release() {
  local release=$1 start=$SECONDS
  local chroot_dir=/var/tmp/dolfinx_ntf-$release
  if [ ! -x "$chroot_dir/usr/bin/apt-get" ] || [ ! -f "$chroot_dir/.complete" ]; then
    if ! command -v debootstrap >/dev/null; then
      apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q debootstrap
    fi
    rm -rf "$chroot_dir"
    echo "other_release: debootstrap $release into $chroot_dir (from $mirror)"
    debootstrap --variant=minbase "$release" "$chroot_dir" "$mirror" > "/var/tmp/debootstrap-$release.log" 2>&1 \
      || { tail -20 "/var/tmp/debootstrap-$release.log" >&2; return 1; }
    if [ "$release" = sid ]; then
      # A mirror's sid Release file can be past its Valid-Until date (measured on this machine's mirror); without
      # this apt-get update fails inside the chroot and nothing installs.
      echo 'Acquire::Check-Valid-Until "false";' > "$chroot_dir/etc/apt/apt.conf.d/99dolfinx_ntf-valid-until"
      chroot "$chroot_dir" apt-get update -q > /dev/null || return 1
    fi
    DEBIAN_FRONTEND=noninteractive chroot "$chroot_dir" apt-get install -y -q --no-install-recommends \
      make git ca-certificates sudo > /dev/null || return 1
    touch "$chroot_dir/.complete"
    echo "other_release: $release chroot made in $((SECONDS - start)) s"
  fi
  mountpoint -q "$chroot_dir/proc" || mount -t proc proc "$chroot_dir/proc"   # MPI needs /proc
  # hwloc and sid's Open MPI (UCX) print errors on every process without /sys
  mountpoint -q "$chroot_dir/sys" || mount -t sysfs -o ro sysfs "$chroot_dir/sys"
  cp /etc/resolv.conf "$chroot_dir/etc/resolv.conf" 2>/dev/null || true

  # A fresh clone of this checkout's HEAD plus its uncommitted changes, so the chroot tests what is here.
  local work=$chroot_dir/root/dolfinx_ntf patch
  rm -rf "$work"
  git clone -q "$root" "$work" || return 1
  patch=$(mktemp)
  git diff --binary HEAD > "$patch"
  [ ! -s "$patch" ] || (cd "$work" && git apply "$patch") || return 1
  rm -f "$patch"
  git ls-files --others --exclude-standard -z | xargs -0 -r cp --parents -t "$work"

  echo "other_release: make ${targets[*]} in Debian $release"
  chroot "$chroot_dir" env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    LANG=C.UTF-8 CI="${CI:-}" bash -c "cd /root/dolfinx_ntf && make ${targets[*]}"
}

failed=()
for release in "${releases[@]}"; do
  start=$SECONDS
  if run_release "$release"; then status=passed; else status=FAILED; failed+=("$release"); fi
  echo "other_release: make ${targets[*]} in Debian $release $status in $((SECONDS - start)) s"
done
[ ${#failed[@]} -eq 0 ] || { echo "other_release: failed in ${failed[*]}" >&2; exit 1; }
