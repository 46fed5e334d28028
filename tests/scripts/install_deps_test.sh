#!/usr/bin/env bash
# ctest "install_deps": scripts/install-deps.sh without root and with packages missing must print the exact
# apt-get install line naming every missing package, stop with exit 2, and install nothing. `id` and
# `dpkg-query` are replaced by stubs on PATH (a non-root uid; two packages reported missing), so the test
# runs the real script on any machine, root or not. A third run with nothing missing must exit 0 silently.
set -euo pipefail
SRC=$(cd "$(dirname "$0")/../.." && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
mkdir -p "$T/bin"
cat > "$T/bin/id" <<'STUB'
#!/bin/sh
[ "$1" = "-u" ] && { echo 1000; exit 0; }
exec /usr/bin/id "$@"
STUB
cat > "$T/bin/dpkg-query" <<'STUB'
#!/bin/bash
# the last argument is the package name; STUB_MISSING lists the packages to report as not installed
for p in $STUB_MISSING; do [ "$p" = "${@: -1}" ] && { echo "unknown ok not-installed"; exit 0; }; done
echo "install ok installed"
STUB
cat > "$T/bin/apt-get" <<'STUB'
#!/bin/sh
echo "apt-get must not run" >&2; touch "$STUB_APT_RAN"; exit 99
STUB
chmod +x "$T/bin/"*
fail() { echo "FAIL: $*"; exit 1; }

set +e
out=$(PATH="$T/bin:$PATH" STUB_MISSING="libclfft-dev munge" STUB_APT_RAN="$T/apt" "$SRC/scripts/install-deps.sh" 2>&1)
rc=$?
set -e
echo "$out"
[ $rc -eq 2 ] || fail "exit code $rc, expected 2"
grep -qx "stex: missing Debian packages: libclfft-dev munge" <<<"$out" || fail "no 'missing Debian packages' line"
grep -qx "stex: run as root:  apt-get update && apt-get install -y --no-install-recommends libclfft-dev munge" <<<"$out" \
  || fail "no exact apt-get install line"
[ ! -e "$T/apt" ] || fail "apt-get ran without root"

set +e
out=$(PATH="$T/bin:$PATH" STUB_MISSING="" STUB_APT_RAN="$T/apt" "$SRC/scripts/install-deps.sh" 2>&1)
rc=$?
set -e
[ $rc -eq 0 ] || fail "nothing missing: exit code $rc, expected 0"
[ -z "$out" ] || fail "nothing missing: printed '$out'"
[ ! -e "$T/apt" ] || fail "apt-get ran with nothing missing"
echo "install_deps: ok"
