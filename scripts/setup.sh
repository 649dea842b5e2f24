#!/usr/bin/env bash
# Make a bare Debian 12 machine ready for dolfinx_ntf; idempotent and fast when everything is there.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

packages=(python3-dolfinx-real python3-gmsh python3-venv python3-pip python3-pytest python3-scipy
          python3-matplotlib libopenblas0-pthread openmpi-bin calculix-ccx)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo_cmd=""
  [ "$(id -u)" = 0 ] || sudo_cmd="sudo"
  echo "setup: installing ${missing[*]}"
  $sudo_cmd apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import dolfinx" 2>/dev/null; then
  rm -rf .venv
  /usr/bin/python3 -m venv --system-site-packages .venv
fi
# Checked from another directory: the repository root itself would make the import succeed.
if ! (cd / && "$root/.venv/bin/python" -c "import dolfinx_ntf") 2>/dev/null; then
  .venv/bin/python -m pip install -q --no-deps --no-build-isolation -e .
fi
