"""A preprocessing run's options as one record (:class:`RunOptions`): the manifest and an
interrupted run's ``run.json`` hold them in the layout of every version so far."""

from expressive_mocap.dataset.derive import Options, RunOptions


def test_the_run_options_are_recorded_in_the_manifest_layout():
    shaping = Options.of("euler", "heading", 15, True)
    options = RunOptions(("positions", "rotations"), "shipped", False, "/data/src", "rust", True, {"hips": "pelvis"},
                         shaping)  # fmt: skip
    assert options.record() == {
        "keep": ["positions", "rotations"], "model": "shipped", "model_float32": False, "source": "/data/src",
        "backend": "rust", "canonical": True, "joint_map": {"hips": "pelvis"}, "rotations": "euler:ZXY",
        "positions": "heading", "fps": 15.0, "mirror": True,
    }  # fmt: skip
    assert list(options.record()) == [
        "keep", "model", "model_float32", "source", "backend", "canonical", "joint_map", "rotations", "positions",
        "fps", "mirror",
    ]  # fmt: skip
    assert options.canonical_map == {"hips": "pelvis"}


def test_clips_on_their_own_skeleton_need_no_map():
    plain = RunOptions(("positions",), None, False, "/data/src", "numpy")
    assert plain.canonical_map is None and plain.record()["joint_map"] is None
    assert RunOptions(("positions",), None, False, "/s", "numpy", canonical=True).canonical_map == {}
    assert plain.record()["rotations"] == "quaternion" and plain.record()["fps"] is None
