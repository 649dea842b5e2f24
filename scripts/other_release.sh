#!/usr/bin/env bash
# Run `make test` (or any make target) of this checkout in a chroot of the *other* supported Debian release:
# Debian 13 (trixie, dolfinx 0.9) on a Debian 12 machine and Debian 12 (bookworm, dolfinx 0.5.2) on a Debian 13
# machine. The chroot is made with debootstrap from the machine's own Debian mirror and cached under /var/tmp, so a
# second run only pays for the tests. Needs root.
#
#   bash scripts/other_release.sh [make target ...]     (default: test-here)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
targets=("${@:-test-here}")

if [ "$(id -u)" != 0 ]; then
  command -v sudo >/dev/null || { echo "other_release: needs root or sudo (debootstrap, chroot, mount)" >&2; exit 1; }
  exec sudo --preserve-env=CI bash "$0" "$@"
fi
start=$SECONDS
here=$(. /etc/os-release && echo "$VERSION_CODENAME")
case "$here" in
  bookworm) other=trixie ;;
  trixie) other=bookworm ;;
  *) echo "other_release: this machine runs Debian '$here'; supported: bookworm (12) and trixie (13)" >&2; exit 1 ;;
esac
chroot_dir=/var/tmp/dolfinx_ntf-$other

mirror=$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)
[ -n "$mirror" ] || mirror=$(awk '/^deb /{print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)
[ -n "$mirror" ] || mirror=http://deb.debian.org/debian

if [ ! -x "$chroot_dir/usr/bin/apt-get" ] || [ ! -f "$chroot_dir/.complete" ]; then
  if ! command -v debootstrap >/dev/null; then
    apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q debootstrap
  fi
  rm -rf "$chroot_dir"
  echo "other_release: debootstrap $other into $chroot_dir (from $mirror)"
  debootstrap --variant=minbase "$other" "$chroot_dir" "$mirror" > /var/tmp/debootstrap-$other.log 2>&1 \
    || { tail -20 /var/tmp/debootstrap-$other.log >&2; exit 1; }
  DEBIAN_FRONTEND=noninteractive chroot "$chroot_dir" apt-get install -y -q --no-install-recommends \
    make git ca-certificates sudo > /dev/null
  touch "$chroot_dir/.complete"
fi
mountpoint -q "$chroot_dir/proc" || mount -t proc proc "$chroot_dir/proc"
cp /etc/resolv.conf "$chroot_dir/etc/resolv.conf" 2>/dev/null || true

# A fresh clone of this checkout's HEAD plus its uncommitted changes, so the chroot tests what is here.
work=$chroot_dir/root/dolfinx_ntf
rm -rf "$work"
git clone -q "$root" "$work"
patch=$(mktemp)
git diff --binary HEAD > "$patch"
[ ! -s "$patch" ] || (cd "$work" && git apply "$patch")
rm -f "$patch"
git ls-files --others --exclude-standard -z | xargs -0 -r cp --parents -t "$work"

echo "other_release: make ${targets[*]} in Debian $other"
chroot "$chroot_dir" env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 CI="${CI:-}" \
  bash -c "cd /root/dolfinx_ntf && make ${targets[*]}"
echo "other_release: make ${targets[*]} in Debian $other done in $((SECONDS - start)) s"
