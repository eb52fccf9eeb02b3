"""Verifies one batch of poses on every GPU of a Ray cluster (docs/python.md, "Scale-out").

One Ray actor per GPU holds a `rangesynth.Verifier` on its own device. The batch is split into
contiguous, near-equal parts, one per actor, the same ranges as the command line's
`--shard i/N`. The parts' results are gathered in order into one dict of arrays, the same as
one `Verifier.verify` call on the whole batch.

Ray gives each GPU actor a GPU by setting CUDA_VISIBLE_DEVICES, which Vulkan does not read. So
the actor asks nvidia-smi for that GPU's UUID (NVIDIA's Vulkan driver reports the same one) and
names it to the Verifier. On a cluster without GPUs, each actor verifies on its node's default
Vulkan device (lavapipe, say); that is how the test suite runs this example.

    python examples/ray_verify.py SENSED.exr MODEL POSES.npy --bindings 1:1 [--actors N]

POSES.npy holds an (N, 4, 4) float64 array. The scores are written to scores.npz beside it.
"""

import argparse
import subprocess
from pathlib import Path

import numpy as np
import ray

import rangesynth


def assigned_device():
    """The UUID of the GPU Ray assigned to this actor, or None where it assigned none."""
    gpus = ray.get_gpu_ids()
    if not gpus:
        return None
    query = ["nvidia-smi", "--query-gpu=uuid", "--format=csv,noheader", "-i", str(gpus[0])]
    return subprocess.run(query, capture_output=True, text=True, check=True).stdout.strip()


@ray.remote
class VerifierActor:
    """A rangesynth.Verifier on this actor's device, kept for the actor's life."""

    def __init__(self):
        self.verifier = rangesynth.Verifier(device=assigned_device())

    def verify(self, sensed, model, poses, bindings, options):
        return self.verifier.verify(sensed, model, poses, bindings, **options)

    def describe(self):
        """The device this actor verifies on, and whether Vulkan validation is on there."""
        return {"device": self.verifier.device_name, "validation": self.verifier.validation_enabled}

    def validation_messages(self):
        return rangesynth.validation_messages()


def make_actors(count=None):
    """One actor per GPU of the cluster, each with a GPU of its own; without GPUs, `count`
    actors (default: one), each with a CPU of its own. More actors than the cluster has GPUs
    (or CPUs) would wait for one for ever, so that is refused."""
    gpus = int(ray.cluster_resources().get("GPU", 0))
    resource, each = ("GPU", {"num_gpus": 1}) if gpus else ("CPU", {"num_cpus": 1})
    count = count or gpus or 1
    available = int(ray.cluster_resources().get(resource, 0))
    if count > available:
        raise ValueError(f"{count} actors need {count} {resource}s; the cluster has {available}")
    return [VerifierActor.options(**each).remote() for _ in range(count)]


def shard_ranges(total, parts):
    """The `--shard i/N` ranges: `parts` contiguous ranges of near-equal length, in order."""
    return [(total * i // parts, total * (i + 1) // parts) for i in range(parts)]


def verify_on_actors(actors, sensed, model, poses, bindings, timeout=None, **options):
    """Verifies `poses` (N, 4, 4), split across `actors`, as `Verifier.verify` would on one
    device: one dict of arrays, one element per pose, in the poses' order. `sensed` and `model`
    are as `verify` takes them; a path is opened by each actor on its own node, so it must name
    a file on a filesystem every node shares. `options` are `verify`'s keywords (shadow,
    effects, tolerance); `timeout`, in seconds, bounds the wait for the results."""
    poses = np.asarray(poses, dtype=np.float64)
    sensed_ref = ray.put(sensed)  # a dict of arrays goes to the object store once, not once per actor
    parts = ray.get(
        [
            actor.verify.remote(sensed_ref, model, poses[start:end], bindings, options)
            for actor, (start, end) in zip(actors, shard_ranges(len(poses), len(actors)))
        ],
        timeout=timeout,
    )
    return {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sensed", help="the sensed range EXR")
    parser.add_argument("model", help="a model file or a builtin: name")
    parser.add_argument("poses", type=Path, help="an .npy file of (N, 4, 4) float64 poses")
    parser.add_argument("--bindings", nargs="+", default=["1:1"], help="scene_label:model_surface pairs")
    parser.add_argument("--shadow", default=None, help="label, depth, exact or none (default: the EXR's)")
    parser.add_argument("--actors", type=int, default=None, help="default: one per GPU (one without GPUs)")
    parser.add_argument("--address", default=None, help="a running Ray cluster's address (default: a local one)")
    args = parser.parse_args()
    ray.init(address=args.address)
    bindings = [tuple(int(k) for k in pair.split(":")) for pair in args.bindings]
    actors = make_actors(args.actors)
    for k, described in enumerate(ray.get([actor.describe.remote() for actor in actors])):
        print(f"actor {k}: {described['device']}")
    options = {"shadow": args.shadow} if args.shadow else {}
    # Absolute paths, which each actor opens on its own node (a shared filesystem's).
    model = args.model if args.model.startswith("builtin:") else str(Path(args.model).resolve())
    sensed = str(Path(args.sensed).resolve())
    result = verify_on_actors(actors, sensed, model, np.load(args.poses), bindings, **options)
    out = args.poses.with_name("scores.npz")
    np.savez(out, **{k: v for k, v in result.items() if k != "overlaps"})
    best = int(np.argmax(result["s"]))
    print(f"{len(result['s'])} poses on {len(actors)} actors; best: pose {best}, s = {result['s'][best]:.4f}; {out}")


if __name__ == "__main__":
    main()
