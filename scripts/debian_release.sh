#!/bin/sh
# Print this machine's (or chroot's) Debian release as dolfinx_ntf's scripts name it: bookworm (12), trixie (13),
# sid (unstable), else the codename /etc/os-release gives. sid and testing both carry the codename of the next
# release (os-release says forky on both, /etc/debian_version says forky/sid on both): apt's sources tell them apart.
codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-unknown}")
case "$codename" in
  bookworm | trixie) echo "$codename"; exit 0 ;;
esac
if cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources 2>/dev/null \
  | grep -v '^[[:space:]]*#' | grep -qE '^(deb[[:space:]].*|Suites:.*)[[:space:]](sid|unstable)([[:space:]]|$)'; then
  echo sid
else
  echo "$codename"
fi
