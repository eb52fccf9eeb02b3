"""rangesynth's verify against a CPU ray tracer, Intel Embree through Open3D's RaycastingScene, in
the same run on the same machine (docs/performance.md, "Against a CPU ray tracer").

rangesynth's side is tools/bench_exact.rs: verify (render, shadow, score) in shadow modes label,
depth and exact, ms a hypothesis, for three workloads: a 12-triangle box at 256², the
~100k-triangle sphere:320 at 256², and the sphere at 1024². Embree's side casts what exact mode
casts, for the same triangles and poses: a primary ray down -z at every pixel centre, then a
shadow ray from each hit toward the camera (a render and a shadow test, no scores). It does so
two ways: each hypothesis posing the vertices and building its own scene (Embree's BVH), and
one scene of the model built once, each hypothesis moving the rays into the model's frame (a
ray tracer's best case). The fastest of three batches of 16 counts. The ratio is the faster
Embree's time over rangesynth's: above 1, rangesynth is ahead. Embree casts in f32, rangesynth's
exact mode in f64; Embree's time includes making its numpy ray arrays, rangesynth's the GPU's
render (label and depth modes) and the scores.

Run from the repository root: `python3 tools/bench_embree.py`. It makes a virtual environment,
target/embree-venv, with Open3D's CPU wheel and numpy, and reruns itself there.
"""

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VENV = ROOT / "target" / "embree-venv"
ROUNDS = 3


def in_venv():
    """Reruns this script in its virtual environment, made and filled first where needed (and
    Open3D's one system library that Debian lacks, libusb, installed)."""
    if subprocess.run(["dpkg-query", "-W", "libusb-1.0-0"], capture_output=True).returncode != 0:
        sudo = [] if os.geteuid() == 0 else ["sudo"]
        subprocess.run(sudo + ["apt-get", "install", "-y", "-qq", "--no-install-recommends", "libusb-1.0-0"], check=True)
    python = VENV / "bin" / "python"
    if not python.exists():
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
    if subprocess.run([str(python), "-c", "import numpy, open3d"], capture_output=True).returncode != 0:
        subprocess.run([str(python), "-m", "pip", "install", "-q", "numpy", "open3d-cpu"], check=True)
    os.execv(str(python), [str(python), __file__, "--in-venv"])


def embree_ms(workload, scene_per_hypothesis):
    """Embree's ms a hypothesis for the workload: the fastest of ROUNDS batches. With
    `scene_per_hypothesis`, each hypothesis poses the vertices and builds its own scene;
    without, one scene of the model is built once, and each hypothesis moves the rays into the
    model's frame instead (a ray tracer's best case: its BVH built once per model)."""
    import numpy as np
    import open3d as o3d

    sensor = workload["sensor"]
    vertices = np.asarray(workload["vertices"], dtype=np.float64)
    triangles = o3d.core.Tensor(np.asarray(workload["triangles"], dtype=np.uint32))
    poses = [np.asarray(p, dtype=np.float64).reshape(4, 4) for p in workload["poses"]]
    cols, rows = np.meshgrid(np.arange(sensor["width"]), np.arange(sensor["height"]))
    x = sensor["origin"][0] + cols.ravel() * sensor["pitch"][0]
    y = sensor["origin"][1] - rows.ravel() * sensor["pitch"][1]
    top = 10.0 + np.abs(vertices).max() * 2
    origins = np.stack([x, y, np.full_like(x, top)], axis=1)
    down = np.array([0.0, 0.0, -1.0])
    theta = np.radians(sensor["theta_deg"])
    to_camera = np.array([np.sin(theta), 0.0, np.cos(theta)])

    def scene_of(points):
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(points.astype(np.float32)), triangles)
        return scene

    def rays(starts, direction):
        out = np.empty((starts.shape[0], 6), dtype=np.float32)
        out[:, :3], out[:, 3:] = starts, direction
        return o3d.core.Tensor(out)

    model_scene = None if scene_per_hypothesis else scene_of(vertices)
    fastest = float("inf")
    for _ in range(ROUNDS):
        start = time.perf_counter()
        for pose in poses:
            rotation, shift = pose[:3, :3], pose[:3, 3]
            if scene_per_hypothesis:
                scene, frame_origins, frame_down, frame_camera = (
                    scene_of(vertices @ rotation.T + shift), origins, down, to_camera)
            else:
                # The sensor's rays in the model's frame: x_model = Rᵀ (x - t).
                scene, frame_origins = model_scene, (origins - shift) @ rotation
                frame_down, frame_camera = rotation.T @ down, rotation.T @ to_camera
            t_hit = scene.cast_rays(rays(frame_origins, frame_down))["t_hit"].numpy()
            hit = np.isfinite(t_hit)
            points = frame_origins[hit] + t_hit[hit, None] * frame_down
            scene.test_occlusions(rays(points, frame_camera), tnear=1e-4)
        fastest = min(fastest, time.perf_counter() - start)
    return fastest * 1e3 / len(poses)


def main():
    if "--in-venv" not in sys.argv:
        in_venv()
    with tempfile.TemporaryDirectory() as tmp:
        command = ["cargo", "run", "--release", "--quiet", "--example", "bench_exact", "--", "--export", tmp]
        ours = [json.loads(line) for line in subprocess.run(command, cwd=ROOT, check=True, capture_output=True,
                                                            text=True).stdout.splitlines()]
        names = list(dict.fromkeys(row["workload"] for row in ours))
        workloads = {name: json.loads((Path(tmp) / f"{name}.json").read_text()) for name in names}
    embree = {name: (embree_ms(w, True), embree_ms(w, False)) for name, w in workloads.items()}
    modes = ["label", "depth", "exact"]
    ms = {(row["workload"], row["mode"]): row["ms"] for row in ours}
    print("ms a hypothesis. Embree: a scene built per hypothesis / one per model with the rays moved.")
    print("ratio: the faster Embree's time over rangesynth's (above 1: rangesynth ahead)")
    print(f"{'workload':<12} {'Embree':>15} " + " ".join(f"{m:>8} {'ratio':>6}" for m in modes))
    for name in names:
        per_hypothesis, per_model = embree[name]
        best = min(per_hypothesis, per_model)
        cells = " ".join(f"{ms[(name, m)]:>8.2f} {best / ms[(name, m)]:>5.2f}×" for m in modes)
        print(f"{name:<12} {per_hypothesis:>7.2f}/{per_model:<7.2f} {cells}")

if __name__ == "__main__":
    main()
