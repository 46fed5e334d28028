#!/usr/bin/env bash
# The README demo: analyse the bundled exemplar, render a texture on the default device.
set -euo pipefail
BUILD=${1:-build}
"$BUILD/cli/stex" info
