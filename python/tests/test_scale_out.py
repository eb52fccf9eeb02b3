"""Scale-out (docs/python.md, "Scale-out"): the command line's `--shard` and the Ray example.

The Ray example runs on a local Ray cluster on this machine's CPUs, each actor's verifier on
lavapipe, and must give the scores one process gives, pose for pose.
"""

import importlib.util
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
import ray

import rangesynth
from test_rangesynth import command_line, hypotheses_file, poses, rendered_by_command_line

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "ray_verify.py"


def load_example():
    spec = importlib.util.spec_from_file_location("ray_verify", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def sensed_exr(tmp_path):
    return rendered_by_command_line(tmp_path)[1] / "range.exr"


def test_shards_concatenated_are_the_unsharded_output_and_the_ray_examples_ranges(tmp_path):
    exr = sensed_exr(tmp_path)
    label = int(rangesynth.read_range_image(exr)["label"].max())
    file = hypotheses_file(tmp_path, poses(*np.linspace(-0.4, 0.4, 11)), label)

    def run(name, *extra):
        out = tmp_path / name
        subprocess.run([command_line(), "verify", str(file), "--scene", str(exr), "--out", str(out), *extra],
                       check=True, capture_output=True)
        return out.read_bytes()

    whole = run("whole.jsonl")
    shards = [run(f"shard{i}.jsonl", "--shard", f"{i}/3") for i in range(3)]
    assert b"".join(shards) == whole
    # The Ray example splits a batch into the same ranges: 11 in three are 3, 4 and 4.
    ranges = load_example().shard_ranges(11, 3)
    assert ranges == [(0, 3), (3, 7), (7, 11)]
    for shard, (start, end) in zip(shards, ranges):
        ids = [json.loads(line)["id"] for line in shard.decode().splitlines()]
        assert ids == [f"h{i}" for i in range(start, end)]


def test_the_ray_examples_scores_equal_one_process(tmp_path):
    example = load_example()
    exr = sensed_exr(tmp_path)
    label = int(rangesynth.read_range_image(exr)["label"].max())
    many = poses(*np.random.default_rng(41).uniform(-0.5, 0.5, 37))
    bindings = [(label, label)]
    alone = rangesynth.Verifier().verify(str(exr), "builtin:box", many, bindings, tolerance=0.05)
    # This machine's CPUs alone, a GPU or not: each actor verifies on lavapipe.
    ray.init(num_cpus=2, num_gpus=0, include_dashboard=False, log_to_driver=False)
    try:
        actors = example.make_actors(2)
        described = ray.get([actor.describe.remote() for actor in actors], timeout=300)
        spread = example.verify_on_actors(actors, str(exr), "builtin:box", many, bindings, timeout=300, tolerance=0.05)
        messages = sum(ray.get([actor.validation_messages.remote() for actor in actors], timeout=300), [])
        # Three actors would wait for a third CPU for ever.
        with pytest.raises(ValueError, match="3 actors need 3 CPUs; the cluster has 2"):
            example.make_actors(3)
    finally:
        ray.shutdown()
    expected = os.environ.get("RANGESYNTH_EXPECT_DEVICE", "")
    for actor in described:
        assert actor["validation"], "the actors' verifiers validate as this process's do"
        assert expected in actor["device"]
    assert not messages, "Vulkan validation reported in an actor:\n" + "\n".join(messages)
    assert set(spread) == set(alone)
    for key in alone:
        if key == "overlaps":
            assert all(np.array_equal(a, b) for a, b in zip(spread[key], alone[key]))
        else:
            np.testing.assert_array_equal(spread[key], alone[key], err_msg=key)
    assert len(set(spread["s"])) > 1, "the poses score differently"
