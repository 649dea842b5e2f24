#!/usr/bin/env bash
# Make a bare Debian 12 (bookworm), Debian 13 (trixie) or Debian unstable (sid) machine ready for dolfinx_ntf;
# idempotent and fast when everything is there. Installs Debian's dolfinx stack (0.5.2, 0.9 or 0.11), OpenBLAS,
# CalculiX ccx 2.20 (the cross-validation oracle) and a .venv that sees Debian's packages; Sphinx, its extensions
# and Chromium for the documentation site. On PATH, `ccx` is always ccx 2.20; on sid, Debian's ccx 2.23 is also
# there as `ccx-2.23`.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
release=$(sh scripts/debian_release.sh)
sudo_cmd=""
[ "$(id -u)" = 0 ] || sudo_cmd="sudo"

packages=(python3-dolfinx-real python3-slepc4py python3-gmsh python3-venv python3-pip python3-pytest python3-scipy
          python3-matplotlib libopenblas0-pthread openmpi-bin calculix-ccx-test
          python3-sphinx python3-myst-parser furo python3-sphinx-gallery chromium)   # make docs, docs-check
# python3-slepc4py: the eigensolver of solvers/modes.py (dolfinx depends on it today; named so that it stays)
ccx_libraries=(libarpack2t64 libgfortran5 liblapack3 libgomp1)   # what bookworm's ccx 2.20 needs, see below
case "$release" in
  bookworm) packages+=(calculix-ccx) ;;
  trixie) packages+=("${ccx_libraries[@]}") ;;
  sid) packages+=(calculix-ccx "${ccx_libraries[@]}") ;;   # calculix-ccx is 2.23 there
  *) echo "setup: Debian '$release' is not supported (bookworm = 12, trixie = 13 and sid = unstable are)" >&2; exit 1 ;;
esac
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  $sudo_cmd apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Debian 13 has no calculix-ccx package and sid's is 2.23. Debian 12's build of ccx 2.20 (and of its SPOOLES solver
# library) runs on their libraries (same sonames: libarpack.so.2, libmpi.so.40, libgfortran.so.5): fetch the two
# bookworm packages from the Debian archive, unpack them under /opt (dpkg's database is left alone) and put a `ccx`
# wrapper in /usr/local/bin (ahead of sid's /usr/bin/ccx on PATH) that finds the unpacked SPOOLES.
ccx_prefix=/opt/dolfinx_ntf-ccx-2.20
ccx_version() { "$1" -v 2>&1 | awk '/Version/{print $NF; exit}' || true; }   # ccx -v exits with status 201
if [ "$release" != bookworm ] && [ "$(ccx_version /usr/local/bin/ccx 2>/dev/null)" != 2.20 ]; then
  echo "setup: fetching CalculiX ccx 2.20 from Debian 12 (bookworm)"
  mirror=$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)
  [ -n "$mirror" ] || mirror=$(awk '/^deb /{print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)
  [ -n "$mirror" ] || mirror=http://deb.debian.org/debian
  apt_dir=$(mktemp -d)
  mkdir -p "$apt_dir/lists/partial" "$apt_dir/archives/partial"
  echo "deb $mirror bookworm main" > "$apt_dir/sources.list"
  apt_opts=(-o "Dir::Etc::SourceList=$apt_dir/sources.list" -o "Dir::Etc::SourceParts=-"
            -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache::Archives=$apt_dir/archives"
            -o "Dir::Cache::pkgcache=" -o "Dir::Cache::srcpkgcache=" -o "APT::Sandbox::User=root")
  $sudo_cmd apt-get -q "${apt_opts[@]}" update > /dev/null
  (cd "$apt_dir" && $sudo_cmd apt-get -q "${apt_opts[@]}" download calculix-ccx/bookworm libspooles2.2/bookworm > /dev/null)
  $sudo_cmd rm -rf "$ccx_prefix"
  for deb in "$apt_dir"/*.deb; do $sudo_cmd dpkg-deb -x "$deb" "$ccx_prefix"; done
  $sudo_cmd rm -rf "$apt_dir"
  $sudo_cmd tee /usr/local/bin/ccx > /dev/null <<WRAP
#!/bin/sh
# CalculiX ccx 2.20 from Debian 12, unpacked by dolfinx_ntf's scripts/setup.sh.
LD_LIBRARY_PATH="$ccx_prefix/usr/lib/x86_64-linux-gnu\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}" exec "$ccx_prefix/usr/bin/ccx" "\$@"
WRAP
  $sudo_cmd chmod 755 /usr/local/bin/ccx
  version=$(/usr/local/bin/ccx -v 2>&1 || true)
  grep -q "Version 2.20" <<< "$version" || { echo "setup: the unpacked ccx does not run: $version" >&2; exit 1; }
fi
if [ "$release" = sid ] && [ ! -e /usr/local/bin/ccx-2.23 ]; then
  [ "$(ccx_version /usr/bin/ccx)" = 2.23 ] || echo "setup: warning: Debian's /usr/bin/ccx is not ccx 2.23" >&2
  $sudo_cmd ln -s /usr/bin/ccx /usr/local/bin/ccx-2.23
fi

if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import dolfinx" 2>/dev/null; then
  rm -rf .venv
  /usr/bin/python3 -m venv --system-site-packages .venv
fi
# Checked from another directory: the repository root itself would make the import succeed.
if ! (cd / && "$root/.venv/bin/python" -c "import dolfinx_ntf") 2>/dev/null; then
  .venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
fi
