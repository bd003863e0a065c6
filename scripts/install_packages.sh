#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the given Debian packages that are missing (apt-get; needs root only then).
# Usage: scripts/install_packages.sh CALLER PACKAGE...   (CALLER prefixes the messages)
set -euo pipefail
caller=$1
shift
missing=()
for p in "$@"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "$caller: installing ${missing[*]}" >&2
  if [ "$(id -u)" -ne 0 ]; then
    echo "$caller: need root to install packages (run as root or install: ${missing[*]})" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
