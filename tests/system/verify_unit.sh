#!/usr/bin/env bash
# systemd-analyze verify on companiond.service, pointed at the built binary (the installed path
# does not exist on a build machine). Any diagnostic about the unit fails the test.
set -euo pipefail
unit_in=$1
binary=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed "s|@CMAKE_INSTALL_FULL_BINDIR@/companiond|$binary|g" "$unit_in" > "$dir/companiond.service"
out=$(systemd-analyze verify "$dir/companiond.service" 2>&1) || { echo "$out"; exit 1; }
if grep -q "companiond.service" <<<"$out"; then
  echo "$out"
  exit 1
fi
echo "systemd-analyze verify: companiond.service OK"
