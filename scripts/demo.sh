#!/usr/bin/env bash
# Set-up (scripts/setup.sh) followed by the main job on the bundled sample data in
# data/synthetic/. Outputs go to ./demo-out/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
mkdir -p demo-out
build/bin/treelobes info data/synthetic/*.las data/synthetic/*.ply
