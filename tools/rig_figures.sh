#!/usr/bin/env bash
# Renders every example rig in rigs/ and copies its range and label previews into docs/rigs/,
# the figures of docs/sensors-and-rigs.md. Run from the repository root after a release build.
set -euo pipefail
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
mkdir -p docs/rigs
for rig in rigs/*.toml; do
  name=$(basename "$rig" .toml)
  ./target/release/rangesynth render "$rig" --out "$out/$name" > /dev/null
  cp "$out/$name/range.png" "docs/rigs/$name-range.png"
  cp "$out/$name/label.png" "docs/rigs/$name-label.png"
done
