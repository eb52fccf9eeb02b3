#!/usr/bin/env bash
# The test command (README, .ci/run): installs what is missing, then runs the whole suite on
# lavapipe with Vulkan validation (synchronization validation included) on in every GPU test.
# Every GPU test asserts that it ran on lavapipe (RANGESYNTH_EXPECT_DEVICE).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh --python
icd=$(ls /usr/share/vulkan/icd.d/lvp_icd.*.json 2>/dev/null | head -n 1)
if [ -z "$icd" ]; then
  echo "lavapipe's ICD file was not found under /usr/share/vulkan/icd.d" >&2
  exit 1
fi
export VK_DRIVER_FILES="$icd" VK_ICD_FILENAMES="$icd" # the second for older loaders
export RANGESYNTH_EXPECT_DEVICE=llvmpipe
cargo test --locked "$@"
# The compute rasterizer through the conformance, stability, analytic, exact-mode and rig
# suites as well (the graphics pipeline ran them above; the exact suite's `columns` and
# `neighbourhood` cases rasterize; the rig suite's against its brute-force reference), and
# through the verification, effects and portability
# suites as a GPU verifies: four hypotheses a coverage dispatch, batches of 16 slots and three
# chunks in flight (lavapipe's defaults are one, 4 and one); only on a full run.
if [ $# -eq 0 ]; then
  RANGESYNTH_TEST_RASTER=compute cargo test --locked --test conformance --test stability --test analytic --test exact \
    --test rigs
  RANGESYNTH_TEST_RASTER=compute RANGESYNTH_TEST_HYPOTHESES_PER_DISPATCH=4 RANGESYNTH_TEST_SLOTS=16 \
    RANGESYNTH_TEST_CHUNKS_IN_FLIGHT=3 cargo test --locked --test verify --test effects --test portability
fi
# The Python package: built from this tree (`pip install .`, maturin's release build) into a
# virtual environment of its own, and its tests run on the same device; only on a full run.
if [ $# -eq 0 ]; then
  venv=target/python-venv
  [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q --upgrade pip 'maturin>=1.7,<2' numpy pytest ray
  # The venv's maturin builds it (no isolated build environment to download each run).
  PATH="$PWD/$venv/bin:$PATH" MATURIN_PEP517_ARGS="--locked" \
    "$venv/bin/python" -m pip install -q --no-deps --no-build-isolation --force-reinstall .
  # The command line `cargo test` built, against which the package's results are compared;
  # validation on, as in the Rust suites (python/tests/conftest.py fails a test on a message).
  target_dir=${CARGO_TARGET_DIR:-target}
  [[ "$target_dir" = /* ]] || target_dir="$PWD/$target_dir"
  (cd python/tests && RANGESYNTH_CLI="$target_dir/debug/rangesynth" RANGESYNTH_VALIDATION=1 \
    ../../"$venv"/bin/python -m pytest -q)
fi
