"""The Python package against geometry worked out by hand and against itself (docs/python.md).

A 16 × 12 orthographic scanner of pitch 0.25 (its first pixel centre at (-1.875, 1.375)) looks
down at the built-in unit box (x and y from -0.5 to 0.5, top at z = 1): the pixels whose centres
lie over the box's top, columns 6 to 9 and rows 4 to 7, hold z = 1 and the box's top label; the
rest see nothing. Run by tools/test.sh on lavapipe after `pip install .`.
"""

import json
import os
import subprocess
import threading

import numpy as np
import pytest

import rangesynth

SENSOR = {
    "kind": "orthographic",
    "width": 16,
    "height": 12,
    "pitch": [0.25, 0.25],
    "origin": [-1.875, 1.375],
    "theta_deg": 0.0,
}


def scene_file(tmp_path, theta_deg=0.0, mode="none"):
    path = tmp_path / "box.toml"
    path.write_text(
        "[sensor]\n"
        + "".join(
            f"{k} = {v!r}\n".replace("'", '"') for k, v in {**SENSOR, "theta_deg": theta_deg}.items()
        )
        + f'[shadow]\nmode = "{mode}"\n[[object]]\nmodel = "builtin:box"\n'
    )
    return path


def test_render_scene_gives_the_boxs_top_by_hand(tmp_path):
    out = rangesynth.render_scene(scene_file(tmp_path))
    assert out["xyz"].shape == (12, 16, 3) and out["xyz"].dtype == np.float32
    assert out["label"].shape == (12, 16) and out["label"].dtype == np.uint32
    assert out["reason"].dtype == np.uint8
    assert out["witness"].dtype == np.uint32  # the scanner's camera is witness 0
    top = np.zeros((12, 16), dtype=bool)
    top[4:8, 6:10] = True
    assert np.array_equal(out["label"] != 0, top)
    assert np.all(out["xyz"][top][:, 2] == 1.0)
    assert np.all(np.isnan(out["xyz"][~top]))
    xs = -1.875 + 0.25 * np.arange(16)
    assert np.allclose(out["xyz"][5, 6:10, 0], xs[6:10])


def sensed_dict(tmp_path):
    out = rangesynth.render_scene(scene_file(tmp_path))
    return {"xyz": out["xyz"], "label": out["label"], "sensor": SENSOR}


def poses(*shifts):
    stack = np.repeat(np.eye(4)[None], len(shifts), axis=0)
    stack[:, 0, 3] = shifts
    return stack


def test_verify_scores_the_true_pose_one_and_a_moved_pose_less(tmp_path):
    top = rangesynth.render_scene(scene_file(tmp_path))["label"].max()
    result = rangesynth.verify(sensed_dict(tmp_path), "builtin:box", poses(0.0, 0.25, 9.0), [(top, top)])
    for key in ["s", "s1", "s2", "s3", "s4", "s5", "s6"]:
        assert result[key].shape == (3,) and result[key].dtype == np.float64
    assert result["s"][0] == 1.0
    assert result["s"][1] < 1.0
    assert result["n_s"][0] == 16 and result["n_i"][0] == 16
    # The box moved off the image renders nothing: rejected, with the reason.
    assert result["s"][2] == 0.0 and "s5" in result["rejected"][2]
    assert result["rejected"][0] == ""


def test_a_verifier_takes_meshes_strided_poses_and_reports_progress(tmp_path):
    verifier = rangesynth.Verifier()
    corners = np.array([[x, y, z] for z in (0, 1) for y in (-0.5, 0.5) for x in (-0.5, 0.5)], dtype=np.float64)
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 2, 6], [0, 6, 4],
             [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6]]
    mesh = rangesynth.Mesh(corners, faces)
    assert (mesh.vertex_count, mesh.triangle_count, mesh.surface_count) == (8, 12, 1)
    label = rangesynth.render_scene(scene_file(tmp_path))["label"].max()
    many = poses(*np.linspace(-0.5, 0.5, 8))
    done = []
    contiguous = verifier.verify(sensed_dict(tmp_path), mesh, many, [(label, 1)], progress=done.append)
    strided = verifier.verify(sensed_dict(tmp_path), mesh, np.asfortranarray(many)[::1], [(label, 1)])
    assert np.array_equal(contiguous["s"], strided["s"])
    assert done and done[-1] == 8 and done == sorted(done)
    # float32 poses are copied to float64.
    single = verifier.verify(sensed_dict(tmp_path), mesh, many.astype(np.float32), [(label, 1)])
    assert np.allclose(single["s"], contiguous["s"])


def test_one_verifier_serves_several_threads(tmp_path):
    verifier = rangesynth.Verifier()
    sensed = sensed_dict(tmp_path)
    label = int(sensed["label"].max())
    many = poses(*np.linspace(-0.3, 0.3, 16))
    alone = verifier.verify(sensed, "builtin:box", many, [(label, label)])["s"]
    results = [None] * 4

    def run(k):
        results[k] = verifier.verify(sensed, "builtin:box", many, [(label, label)])["s"]

    threads = [threading.Thread(target=run, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        assert np.array_equal(r, alone)


def test_errors_are_rangesynth_errors_with_the_librarys_message(tmp_path):
    sensed = sensed_dict(tmp_path)
    with pytest.raises(rangesynth.Error, match="poses must have 3 dimensions"):
        rangesynth.verify(sensed, "builtin:box", np.eye(4), [(1, 1)])
    nan = poses(0.0)
    nan[0, 1, 3] = np.nan
    with pytest.raises(rangesynth.Error, match="hypothesis \"0\""):
        rangesynth.verify(sensed, "builtin:box", nan, [(1, 1)])
    with pytest.raises(rangesynth.Error, match="xyz"):
        rangesynth.verify({**sensed, "xyz": sensed["xyz"][:, :, :2]}, "builtin:box", poses(0.0), [(1, 1)])
    with pytest.raises(rangesynth.Error, match="poses is not an array of float64: it must hold real numbers"):
        rangesynth.verify(sensed, "builtin:box", [[["a"] * 4] * 4], [(1, 1)])
    # Labels are converted only where no value changes: not from floats, nor from -1.
    with pytest.raises(rangesynth.Error, match="sensed \"label\" is not an array of uint32: it must hold integers"):
        rangesynth.verify({**sensed, "label": sensed["label"] + 0.5}, "builtin:box", poses(0.0), [(1, 1)])
    with pytest.raises(rangesynth.Error, match="holds -1 to"):
        rangesynth.verify({**sensed, "label": sensed["label"].astype(np.int64) - 1}, "builtin:box", poses(0.0), [(1, 1)])
    with pytest.raises(rangesynth.Error, match="face index -1 is not a vertex index"):
        rangesynth.Mesh(np.zeros((3, 3)), [[0, 1, 2], [-1, 1, 2]])
    ints = rangesynth.verify({**sensed, "label": sensed["label"].astype(np.int64)}, "builtin:box", poses(0.0), [(1, 1)])
    assert ints["s"][0] == rangesynth.verify(sensed, "builtin:box", poses(0.0), [(1, 1)])["s"][0]
    # The sensed arrays are 12 × 16; a sensor of another size is refused, naming both.
    wider = {**sensed, "sensor": {**SENSOR, "width": 17}}
    with pytest.raises(rangesynth.Error, match="17"):
        rangesynth.verify(wider, "builtin:box", poses(0.0), [(1, 1)])
    with pytest.raises(rangesynth.Error, match="binding"):
        rangesynth.verify(sensed, "builtin:box", poses(0.0), [(1, 9)])
    with pytest.raises(rangesynth.Error, match="builtin"):
        rangesynth.verify(sensed, "builtin:no-such-model", poses(0.0), [(1, 1)])
    with pytest.raises(rangesynth.Error, match="refers to vertex 7"):
        rangesynth.Mesh(np.zeros((3, 3)), [[0, 1, 7]])
    with pytest.raises(rangesynth.Error):
        rangesynth.render_scene(tmp_path / "missing.toml")
    with pytest.raises(rangesynth.Error, match="rasterizer"):
        rangesynth.render_scene(scene_file(tmp_path), raster="fastest")
    assert issubclass(rangesynth.Error, Exception)


def test_devices_lists_the_device_the_renderer_runs_on():
    listed = rangesynth.devices()
    assert listed and all(set(d) == {"index", "name", "uuid", "kind"} for d in listed)
    # NVIDIA's tools write a UUID with "GPU-" before it.
    for choice in [listed[0]["uuid"], "GPU-" + listed[0]["uuid"], listed[0]["index"]]:
        renderer = rangesynth.Renderer(device=choice)
        assert renderer.device_name == listed[0]["name"]
    with pytest.raises(rangesynth.Error, match="no usable Vulkan device"):
        rangesynth.Renderer(device="no-such-device")
    expected = os.environ.get("RANGESYNTH_EXPECT_DEVICE")
    if expected:
        assert expected in renderer.device_name


def test_validation_is_on_in_the_packages_renderers():
    # conftest.py fails a test on any message; that means something only where it is on.
    assert rangesynth.Renderer().validation_enabled


def command_line():
    """The rangesynth command line that `cargo test` built (tools/test.sh names it)."""
    path = os.environ.get("RANGESYNTH_CLI", "")
    assert os.path.isfile(path), "RANGESYNTH_CLI must name the rangesynth binary (tools/test.sh sets it)"
    return path


def rendered_by_command_line(tmp_path):
    """The box scene at θ = 30° with depth-mode shadows, and the directory the command line's
    `render` wrote it to."""
    scene = scene_file(tmp_path, theta_deg=30.0, mode="depth")
    out = tmp_path / "out"
    subprocess.run([command_line(), "render", str(scene), "--out", str(out)], check=True, capture_output=True)
    return scene, out


def hypotheses_file(tmp_path, many, label, **keys):
    """A hypotheses file of the box at each of `many` poses, ids h0, h1, …, its label bound to
    the box's surface; `keys` are the file's other top-level keys."""
    hypotheses = [
        {"id": f"h{i}", "model": "builtin:box", "pose": p.tolist(), "bindings": [[label, label]]}
        for i, p in enumerate(many)
    ]
    file = tmp_path / "hypotheses.json"
    file.write_text(json.dumps({**keys, "hypotheses": hypotheses}))
    return file


def test_render_and_verify_equal_the_command_lines_bit_for_bit(tmp_path):
    scene, out = rendered_by_command_line(tmp_path)
    exr = rangesynth.read_range_image(out / "range.exr")
    ours = rangesynth.render_scene(scene)
    for key in ["xyz", "label", "reason", "witness"]:
        assert ours[key].dtype == exr[key].dtype
        np.testing.assert_array_equal(ours[key], exr[key])
    assert exr["sensor"]["theta_deg"] == 30.0
    label = int(exr["label"].max())
    many = poses(*np.linspace(-0.4, 0.4, 9))
    file = hypotheses_file(tmp_path, many, label, tolerance=0.05)
    scores = tmp_path / "scores.jsonl"
    command = [command_line(), "verify", str(file), "--scene", str(out / "range.exr"), "--out", str(scores)]
    subprocess.run(command, check=True, capture_output=True)
    lines = [json.loads(line) for line in scores.read_text().splitlines()]
    result = rangesynth.verify(str(out / "range.exr"), "builtin:box", many, [(label, label)], tolerance=0.05)
    for key in ["s", "s1", "s2", "s3", "s4", "s5", "s6"]:
        assert [line[key] for line in lines] == result[key].tolist()
    for i, line in enumerate(lines):
        counts = line["counts"]
        for key in ["n1_plus", "n1_minus", "n0", "n1", "n_s", "n_i"]:
            assert counts[key] == result[key][i], key
        assert counts["surface_population"] == result["surface_population"][i].tolist()
        assert counts["overlaps"] == result["overlaps"][i].tolist()
    assert any(len(o) for o in result["overlaps"]), "some pose overlaps the box's label"
    # The labels table is the command line's labels.json.
    labels = json.loads((out / "labels.json").read_text())["labels"]
    table = ours["labels"]
    assert table.dtype.names == ("label", "object", "model", "surface", "surface_name")
    assert [dict(zip(table.dtype.names, row.tolist())) for row in table] == labels


def test_a_batch_of_1024_poses_equals_1024_single_calls(tmp_path):
    sensed = sensed_dict(tmp_path)
    label = int(sensed["label"].max())
    rng = np.random.default_rng(39)
    many = poses(*rng.uniform(-0.6, 0.6, 1024))
    verifier = rangesynth.Verifier()
    batch = verifier.verify(sensed, "builtin:box", many, [(label, label)])
    single = np.concatenate([verifier.verify(sensed, "builtin:box", p[None], [(label, label)])["s"] for p in many])
    assert np.array_equal(batch["s"], single)


def test_a_call_holds_its_poses_to_the_budget_before_copying_any(tmp_path):
    # A million poses as a view of one (128 bytes), which the call would copy, hypothesis by
    # hypothesis, into about a gigabyte: refused under 64 MiB, naming them, before any copy.
    sensed = sensed_dict(tmp_path)
    verifier = rangesynth.Verifier(memory_budget="64M")
    million = np.broadcast_to(np.eye(4), (1_000_000, 4, 4))
    with pytest.raises(rangesynth.Error, match="1000000 poses needs about"):
        verifier.verify(sensed, "builtin:box", million, [(1, 1)])
    # The refusal held nothing: a call that fits runs under the same budget.
    assert verifier.verify(sensed, "builtin:box", million[:2], [(1, 1)])["s"].shape == (2,)


def test_a_renderer_kept_for_many_calls_does_not_hold_each_scene_against_its_budget(tmp_path):
    # Each call's scene is charged for that call alone: 100 renders of a scene whose parse the
    # budget holds a few times over fit a 1 MiB budget.
    renderer = rangesynth.Renderer(memory_budget="1M")
    scene = scene_file(tmp_path)
    first = renderer.render(scene)
    for _ in range(100):
        assert np.array_equal(renderer.render(scene)["label"], first["label"])
