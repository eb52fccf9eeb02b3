"""What a verification through Python costs over the same one through the Rust library.

One batch of 1,024 `builtin:box` poses about the example's sensed step (docs/example/sensed.toml,
256², depth-mode shadows) is verified in one call, first through the library
(tools/bench_python_baseline.rs, run as a separate process) and then through
`rangesynth.Verifier.verify` with the sensed image as numpy arrays. Both sides use the same
device and the same settings, and both warm up first. The two sides take turns call by call
(the library's process waits for a line, verifies, and answers with its time), and each side's
fastest call counts, as does the median of the pairs' ratios. Calls of one pose, timed the
same way, give a call's fixed cost. The Python call's time includes everything it adds
to the batch: it reads the arrays, prepares the sensed image, builds the hypotheses and returns
numpy arrays. The library's time is `Verifier::verify` alone.

Run from the repository root with the Python package installed (tools/test.sh builds it into
target/python-venv):

    target/python-venv/bin/python tools/bench_python.py [--quick]

RANGESYNTH_DEVICE picks the device for both sides.
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import rangesynth

ROOT = Path(__file__).resolve().parents[1]
BATCH = 1024


def poses():
    """The batch: the example's true pose (turned 25° about z, at (0.3, -0.2)), turned a further
    0 to 2° and moved up to a pixel (0.02) in x and y, from a fixed seed."""
    rng = np.random.default_rng(40)
    turn = np.radians(25.0 + rng.uniform(0.0, 2.0, BATCH))
    stack = np.repeat(np.eye(4)[None], BATCH, axis=0)
    stack[:, 0, 0], stack[:, 0, 1] = np.cos(turn), -np.sin(turn)
    stack[:, 1, 0], stack[:, 1, 1] = np.sin(turn), np.cos(turn)
    stack[:, 0, 3] = 0.3 + rng.uniform(-0.02, 0.02, BATCH)
    stack[:, 1, 3] = -0.2 + rng.uniform(-0.02, 0.02, BATCH)
    return stack


def library_seconds(library, batch):
    """One call through the library, in its own process, which answers with its seconds."""
    library.stdin.write(f"{len(batch)}\n")
    library.stdin.flush()
    return float(library.stdout.readline())


def python_seconds(verifier, sensed, batch):
    start = time.perf_counter()
    verifier.verify(sensed, "builtin:box", batch, [(1, 1), (2, 1)], shadow="depth", tolerance=0.1)
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="two calls a side, not ten")
    args = parser.parse_args()
    rounds = 2 if args.quick else 10
    build = ["cargo", "build", "--release", "--quiet", "--example", "bench_python_baseline", "--message-format=json"]
    built = subprocess.run(build, cwd=ROOT, check=True, capture_output=True, text=True).stdout
    binary = next(
        json.loads(line)["executable"]
        for line in built.splitlines()
        if '"bench_python_baseline"' in line and json.loads(line).get("executable")
    )
    batch = poses()
    verifier = rangesynth.Verifier()
    sensed = rangesynth.render_scene(ROOT / "docs" / "example" / "sensed.toml")
    python_seconds(verifier, sensed, batch[:1])  # warm up, as the library's side does
    with tempfile.TemporaryDirectory() as tmp:
        poses_file = Path(tmp) / "poses.json"
        poses_file.write_text(json.dumps([p.flatten().tolist() for p in batch]))
        with subprocess.Popen([binary, str(poses_file)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              text=True) as library:
            assert library.stdout.readline().strip() == "ready"
            rows = []
            for poses_a_call, calls in [(BATCH, rounds), (1, 10 * rounds)]:
                part = batch[:poses_a_call]
                pairs = [(library_seconds(library, part), python_seconds(verifier, sensed, part)) for _ in range(calls)]
                rows.append((poses_a_call, calls, pairs))
            library.stdin.close()
    print(f"device: {verifier.device_name}")
    print("one call a batch, the two sides in turns:")
    print(f"{'poses':>6} {'calls':>6} {'library (ms)':>13} {'Python (ms)':>12} {'ratio of fastest':>17} "
          f"{'median ratio':>13} {'difference (ms)':>16}")
    for poses_a_call, calls, pairs in rows:
        best_library, best_python = min(p[0] for p in pairs), min(p[1] for p in pairs)
        median_ratio = float(np.median([p[1] / p[0] for p in pairs]))
        print(f"{poses_a_call:>6} {calls:>6} {best_library * 1e3:>13.2f} {best_python * 1e3:>12.2f} "
              f"{best_python / best_library:>17.3f} {median_ratio:>13.3f} {(best_python - best_library) * 1e3:>16.2f}")


if __name__ == "__main__":
    sys.exit(main())
