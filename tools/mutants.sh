#!/usr/bin/env bash
# Mutation testing of the host-side logic: cargo-mutants over the modules below, each with the
# test targets that exercise it, on lavapipe (as tools/test.sh runs them). Results, and each
# surviving mutant's fate (killed by a new test, or equivalent and why), are in
# docs/mutation-testing.md.
#
#   tools/mutants.sh [FILE...]      the files named (default: every file in the table)
#
# Each file's outcomes land in target/mutants/<file path with / as _>/mutants.out. The tree is
# mutated in place (cargo-mutants --in-place): run it in a worktree of its own, never in one you
# are editing. Host code is built at opt-level 1 (dependencies stay at 3): each mutant is a
# rebuild of the crate, which at the test profile's opt-level 3 takes minutes.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# The files named, as paths from the repository's root, wherever they were named from.
files=()
for file in "$@"; do
  files+=("$(realpath --relative-to="$root" "$file")")
done
cd "$root"
command -v cargo-mutants >/dev/null || cargo install --locked cargo-mutants@27.1.0
icd=$(ls /usr/share/vulkan/icd.d/lvp_icd.*.json 2>/dev/null | head -n 1 || true)
if [ -z "$icd" ]; then
  echo "lavapipe's ICD file was not found under /usr/share/vulkan/icd.d (run tools/setup.sh)" >&2
  exit 1
fi
export VK_DRIVER_FILES="$icd" VK_ICD_FILENAMES="$icd" RANGESYNTH_EXPECT_DEVICE=llvmpipe
export CARGO_PROFILE_TEST_OPT_LEVEL=1

# The modules, and the test targets that exercise each.
declare -A TESTS=(
  [src/verify/scores.rs]="--lib --test scores --test verify"
  [src/verify/counts.rs]="--lib --test scores --test verify"
  [src/verify/area.rs]="--lib --test scores --test verify"
  [src/verify/sensed.rs]="--lib --test verify --test files"
  [src/verify/hypothesis.rs]="--lib --test verify --test hostile --test hostile_two"
  [src/shadow.rs]="--lib --test exact --test conformance --test cli"
  [src/pose.rs]="--lib --test verify --test hostile_two"
  [src/effects.rs]="--lib --test effects --test hostile_two --test cli"
  [src/sensor/scanner.rs]="--lib --test f32_boundaries --test analytic --test conformance --test hostile_two"
  [src/sensor/grid.rs]="--lib --test f32_boundaries --test conformance"
  [src/sensor/orthographic.rs]="--lib --test f32_boundaries --test hostile_two --test cli"
  [src/sensor/pinhole.rs]="--lib --test rigs"
  [src/sensor/witness.rs]="--lib --test rigs"
  [src/sensor/file.rs]="--lib --test rigs --test cli --test hostile"
  [src/sensor/mod.rs]="--lib --test rigs"
  [src/limits.rs]="--lib --test memory --test hostile"
  [src/untrusted.rs]="--lib --test hostile --test hostile_two"
  [src/io/atomic.rs]="--lib --test outputs"
  [src/io/input_file.rs]="--lib --test hostile --test files"
  [src/scene.rs]="--lib --test hostile --test hostile_two --test cli"
)
if [ ${#files[@]} -eq 0 ]; then
  mapfile -t files < <(printf '%s\n' "${!TESTS[@]}" | sort)
fi
for file in "${files[@]}"; do
  tests=${TESTS[$file]:?"$file: not in the table of tools/mutants.sh"}
  out="target/mutants/${file//\//_}"
  mkdir -p "$out"
  # The unmutated tree is tested first (cargo-mutants' baseline): where it fails, nothing
  # is measured. Exit status 2 means mutants survived, 3 that some timed out: the outcomes
  # say which.
  status=0
  args=()
  for arg in $tests; do args+=("--cargo-arg=$arg"); done
  cargo mutants --in-place --no-shuffle --timeout 300 -f "$file" --output "$out" "${args[@]}" || status=$?
  case $status in 0 | 2 | 3) ;; *) exit "$status" ;; esac
  echo "$file: caught $(wc -l < "$out/mutants.out/caught.txt"), missed $(wc -l < "$out/mutants.out/missed.txt"), unviable $(wc -l < "$out/mutants.out/unviable.txt"), timeouts $(wc -l < "$out/mutants.out/timeout.txt")"
done
