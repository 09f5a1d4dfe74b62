#!/usr/bin/env bash
# `cmake --install` into a staging prefix installs the binary, the config and the system files.
set -euo pipefail
build_dir=$1
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
cmake --install "$build_dir" --prefix "$stage/usr" > /dev/null
for f in usr/bin/companiond usr/bin/companion-candiag usr/bin/companion-tracker usr/bin/companion-lidar \
         usr/etc/companion/companiond.yaml \
         usr/lib/systemd/system/companiond.service usr/lib/systemd/network/80-can0.network \
         usr/lib/udev/rules.d/70-amfitrack.rules usr/lib/sysusers.d/companion.conf; do
  [[ -e "$stage/$f" ]] || { echo "missing after install: $f"; exit 1; }
done
"$stage/usr/bin/companiond" --check-config "$stage/usr/etc/companion/companiond.yaml"
echo "install OK"
