#!/usr/bin/env bash
# The GPU checks, for a machine with a Vulkan GPU but neither a Rust toolchain nor a package
# registry (such as the device machine some sessions are lent: README, "Tests").
#
#   tools/device_kit.sh pack   here: builds the benchmark and the GPU test suites (release
#                              profile) and downloads the Vulkan loader, the validation
#                              layers and libglvnd as Debian packages, into target/device-kit;
#                              with DEVICE_KIT_BASELINE=REV, the benchmark at REV too
#                              (bench_verify_baseline), for an A/B on one machine
#   tools/device_kit.sh run    there, with target/device-kit carried: unpacks the packages the
#                              machine lacks, runs the rasterizers' benchmark and the cold
#                              start, then every suite with the graphics pipeline and again
#                              with the compute rasterizer, validation on, on the GPU; five
#                              files (the device, the benchmark, a log a rasterizer, a
#                              summary; with a baseline, its benchmark's log too,
#                              bench-baseline.log) under $OUT (or target/device-kit/out).
#                              Exits 0 when every suite passed.
#   tools/device_kit.sh suite NAME [ARGS]
#                              there: one of the kit's binaries (a suite as in `suites` below,
#                              with libtest's filters and options, or bench_verify), on the
#                              machine run readies.
#
# RANGESYNTH_EXPECT_DEVICE (default NVIDIA) is what the device's name must contain, and
# DEVICE_KIT_BENCH_SECONDS (default 300) bounds each run of a benchmark, so that the whole
# fits in one command of the device tool (10 minutes; with a baseline there are four runs: on
# an H100 each took about 15 s).
set -euo pipefail
cd "$(dirname "$0")/.."
kit=target/device-kit
suites=(conformance stability analytic compute_raster exact verify effects portability pipeline_cache rigs)
# The Vulkan loader, the validation layers, and libglvnd: NVIDIA's Vulkan driver is
# libGLX_nvidia.so.0, which needs libglvnd's dispatch library.
debs=(libvulkan1 vulkan-validationlayers libglvnd0 libglx0 libgl1 libegl1 libopengl0 libgles2)
# The library each package brings, by which prepare tells whether the machine has it.
declare -A deb_library=(
    [libvulkan1]=libvulkan.so.1 [libglvnd0]=libGLdispatch.so.0 [libglx0]=libGLX.so.0
    [libgl1]=libGL.so.1 [libegl1]=libEGL.so.1 [libopengl0]=libOpenGL.so.0 [libgles2]=libGLESv2.so.2
)

pack() {
    tools/setup.sh
    rm -rf "$kit"
    mkdir -p "$kit/bin" "$kit/debs"
    cargo build --release --locked --example bench_verify
    cp target/release/examples/bench_verify "$kit/bin/"
    local tests=()
    for suite in "${suites[@]}"; do tests+=(--test "$suite"); done
    # cargo names each test binary it built: "Executable tests/NAME.rs (target/release/deps/NAME-HASH)".
    cargo test --release --locked --no-run "${tests[@]}" 2>&1 | tee "$kit/build.log" >&2
    for suite in "${suites[@]}"; do
        local binary
        binary=$(sed -n "s|.*Executable tests/$suite.rs (\(.*\))|\1|p" "$kit/build.log")
        [ -x "$binary" ] || { echo "no test binary for $suite in cargo's output" >&2; exit 1; }
        cp "$binary" "$kit/bin/$suite"
    done
    if [ -n "${DEVICE_KIT_BASELINE:-}" ]; then
        pack_baseline "$DEVICE_KIT_BASELINE"
    fi
    strip "$kit"/bin/*
    (cd "$kit/debs" && { apt-get download "${debs[@]}" 2>/dev/null ||
        { apt-get update -qq && apt-get download "${debs[@]}"; }; })
    du -sh "$kit" >&2
}

# The benchmark as built at git revision $1, as the kit's bench_verify_baseline: `run` then
# times the two in turn, on one machine (a device machine is fresh at every start, and one
# build's figures moved by a seventh from run to run on one H100). Built in a worktree of its
# own, into target/baseline-build.
pack_baseline() {
    local tree
    tree=$(mktemp -d)
    git worktree add --detach "$tree" "$1" >&2
    cargo build --release --locked --example bench_verify --manifest-path "$tree/Cargo.toml" \
        --target-dir target/baseline-build
    git worktree remove --force "$tree"
    cp target/baseline-build/release/examples/bench_verify "$kit/bin/bench_verify_baseline"
}

# Readies this machine for the kit's binaries: the packages it lacks, the NVIDIA driver's
# manifest, the device expected.
prepare() {
    if [ ! -d "$kit/bin" ]; then
        echo "no $kit here: run tools/device_kit.sh pack where rangesynth builds, and carry $kit" >&2
        exit 2
    fi
    # The loader, libglvnd and the layers from the kit, only where the machine lacks them.
    local deb
    for deb in "${!deb_library[@]}"; do
        if ! ldconfig -p | grep -F "${deb_library[$deb]} (libc6,x86-64" > /dev/null; then
            dpkg -x "$kit"/debs/"$deb"_*.deb /
        fi
    done
    if [ ! -e /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ]; then
        dpkg -x "$kit"/debs/vulkan-validationlayers_*.deb /
    fi
    ldconfig
    local nvidia=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    if [ -z "${VK_DRIVER_FILES:-}" ] && [ -e "$nvidia" ]; then
        export VK_DRIVER_FILES=$nvidia VK_ICD_FILENAMES=$nvidia # the second for older loaders
    fi
    export RANGESYNTH_EXPECT_DEVICE=${RANGESYNTH_EXPECT_DEVICE:-NVIDIA}
}

run() {
    prepare
    local out=${OUT:-$kit/out}
    mkdir -p "$out"
    rm -f "$out"/suites-*.log "$out"/bench*.log
    # What the kit's binaries, built elsewhere, meet here.
    {
        nvidia-smi --query-gpu=name,driver_version --format=csv,noheader || true
        grep -h PRETTY_NAME /etc/os-release || true
        ldd --version | head -n 1 || true
        ls /usr/local/nvidia/share/vulkan/icd.d /usr/share/vulkan/icd.d /etc/vulkan/icd.d || true
        # The loader's account of the drivers it found and loaded, for one short test.
        VK_LOADER_DEBUG=error,driver timeout 60 "$kit/bin/conformance" box_matches_the_reference 2>&1 |
            grep -v '^$' | head -n 60 || true
    } > "$out/device.txt" 2>&1
    # The benchmark, or where the kit has a baseline, the baseline and the benchmark in turn,
    # twice: each run at most DEVICE_KIT_BENCH_SECONDS.
    local bench rounds=1
    [ ! -x "$kit/bin/bench_verify_baseline" ] || rounds=2
    for round in $(seq "$rounds"); do
        for bench in bench_verify_baseline bench_verify; do
            [ -x "$kit/bin/$bench" ] || continue
            local log=$out/bench.log
            [ "$bench" = bench_verify ] || log=$out/bench-baseline.log
            echo "=== $bench, round $round" >> "$log"
            timeout "${DEVICE_KIT_BENCH_SECONDS:-300}" "$kit/bin/$bench" --rasters >> "$log" 2>&1 ||
                echo "$bench: exit $? (124: stopped at DEVICE_KIT_BENCH_SECONDS)" >> "$log"
        done
    done
    # Process start to first verified hypothesis, with an empty pipeline cache and a warm one
    # (a GPU's cache holds the driver's compiled code; lavapipe's holds none).
    timeout 120 "$kit/bin/bench_verify" --cold-start >> "$out/bench.log" 2>&1 ||
        echo "bench_verify --cold-start: exit $?" >> "$out/bench.log"
    # A pinhole rig beside the scanner, with each rasterizer (the rigs' GPU crossover is
    # unmeasured: render::Crossover::for_rig).
    timeout 180 "$kit/bin/bench_verify" --rigs >> "$out/bench.log" 2>&1 ||
        echo "bench_verify --rigs: exit $?" >> "$out/bench.log"
    # Much as tools/test.sh runs them: every suite with the graphics pipeline, then all but
    # compute_raster (which compares the two itself) with the compute rasterizer, which on a
    # GPU covers four hypotheses a dispatch, in runs of 16 slots, three chunks in flight. One log
    # a rasterizer: the device tool brings back at most 8 files.
    for raster in graphics compute; do
        for suite in "${suites[@]}"; do
            [ "$raster/$suite" != compute/compute_raster ] || continue
            local log=$out/suites-$raster.log status=passed
            echo "=== $suite ($raster)" >> "$log"
            RANGESYNTH_TEST_RASTER=$raster "$kit/bin/$suite" >> "$log" 2>&1 || status=FAILED
            echo "$suite ($raster): $status"
        done
    done | tee "$out/summary.txt"
    ! grep -q FAILED "$out/summary.txt"
}

case "${1:-}" in
    pack) pack ;;
    run) run ;;
    suite)
        # One binary, with the test filters and options given (RANGESYNTH_TEST_RASTER as set).
        prepare
        [ $# -ge 2 ] && [ -x "$kit/bin/$2" ] || { echo "usage: tools/device_kit.sh suite NAME [ARGS]" >&2; exit 2; }
        exec "$kit/bin/$2" "${@:3}"
        ;;
    *)
        echo "usage: tools/device_kit.sh pack|run|suite NAME [ARGS]" >&2
        exit 2
        ;;
esac
