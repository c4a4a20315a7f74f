"""The shipped exaggeration models (exaggeration/zoo.py): what ships, how `exaggerate` picks one
without --model, and that benches/build_models.py's recipe gives the shipped file back. The
procedural walk needs no data; the rebuild and the held-out takes need Bandai-Namco dataset-2
(CC BY-NC 4.0)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.exaggeration import ExaggerationModel
from expressive_mocap.exaggeration.model import COMPACT_CYCLES
from expressive_mocap.exaggeration.zoo import (
    ACTIONS,
    AXES,
    SIGNATURE_MARGINS,
    build,
    candidates,
    choose,
    file_name,
    index_records,
    shipped_models,
    signature,
    training_clips,
)
from expressive_mocap.procedural import walk_and_wave

DATA = Path(em.__file__).parent / "data" / "exaggeration"


def test_what_ships_passed_its_validation_and_fits_in_five_megabytes():
    records = index_records()  # every model of the recipe, shipped or not
    assert [(r["action"], r["axis"]) for r in records] == [(a, x) for x in AXES for a in ACTIONS]
    shipped = shipped_models()
    assert [m.action for m in shipped] == [r["action"] for r in records if r["shipped"]] and shipped
    for r in records:  # a model ships exactly when no bar failed, and only shipped ones have files
        assert r["shipped"] == (not r["failed"]) == (DATA / r["file"]).is_file()
    for m in shipped:
        assert m.record["swap_ratio"] <= 0.35 and m.record["warp_ratio_worst"] <= 0.5
        assert m.record["estimate_within"] >= 0.9 and m.record["chosen_right"] >= 0.95
        model = m.load()  # compact: a few cycles per performance, read back as float64
        counts = np.unique(model.cycle_performance, axis=0, return_counts=True)[1]
        assert counts.max() <= COMPACT_CYCLES and model.trajectories.dtype == np.float64
    assert sum(p.stat().st_size for p in DATA.iterdir()) < 5e6


def test_a_compact_model_keeps_every_performance_within_half_precision():
    shipped = shipped_models()[0].load()
    again = ExaggerationModel.load(shipped.to_bytes(compact=True))
    np.testing.assert_allclose(again.trajectories, shipped.trajectories, rtol=1e-3, atol=1e-4)
    np.testing.assert_array_equal(again.mappings, shipped.mappings)


def test_exaggerate_without_a_model_picks_the_walk_model_and_says_so(tmp_path, capsys):
    walk = walk_and_wave(seconds=4.0).walk
    em.write_bvh(walk, tmp_path / "walk.bvh")
    assert (
        main(["exaggerate", "--input", str(tmp_path / "walk.bvh"), "--to", "3", "-o", str(tmp_path / "out.bvh")]) == 0
    )
    said = capsys.readouterr().out
    assert "model: the shipped walk (energy) (exhausted 1 < normal 2 < active 3), fit residual" in said
    assert em.read_bvh(tmp_path / "out.bvh").skeleton.names == walk.skeleton.names


def test_a_motion_of_no_shipped_action_is_refused_with_every_residual(tmp_path, capsys):
    standing = walk_and_wave(seconds=4.0).waving
    standing = em.Motion(
        standing.skeleton,
        standing.rotations,
        np.broadcast_to(standing.translations[:1], standing.translations.shape).copy(),
        standing.frame_time,
    )  # waving on the spot: no travel, so no walk
    em.write_bvh(standing, tmp_path / "wave.bvh")
    out = tmp_path / "out.bvh"
    assert main(["exaggerate", "--input", str(tmp_path / "wave.bvh"), "--to", "3", "-o", str(out)]) != 0
    said = capsys.readouterr().err
    assert "no shipped model fits this motion" in said and "walk (energy)" in said and "not its action" in said
    assert not out.exists()
    with pytest.raises(em.errors.ArgumentError, match="no shipped model of action juggle"):
        candidates("juggle")
    argv = ["exaggerate", "--input", str(tmp_path / "wave.bvh"), "--to", "3", "-o", str(out), "--action", "juggle"]
    assert main(argv) != 0 and "no shipped model of action juggle" in capsys.readouterr().err
    assert main([*argv, "--model", str(tmp_path / "m.npz")]) != 0
    assert "give them without --model" in capsys.readouterr().err and not out.exists()


def test_the_models_command_lists_every_model_and_why_it_did_not_ship(capsys):
    assert main(["models"]) == 0
    said = capsys.readouterr().out
    for r in index_records():
        assert r["action"] in said
    assert "yes" in said and "no (" in said


def test_the_recipe_rebuilds_the_shipped_walk_model(bandai2_dir):
    rebuilt = ExaggerationModel.load(
        build(training_clips(bandai2_dir, "walk", "energy"), "walk").to_bytes(compact=True)
    )
    shipped = ExaggerationModel.load((DATA / file_name("walk", "energy")).read_bytes())
    for name in ("basis", "mappings", "lower", "upper", "reference", "overall"):
        np.testing.assert_allclose(getattr(rebuilt, name), getattr(shipped, name), rtol=1e-9, atol=1e-9, err_msg=name)
    np.testing.assert_array_equal(rebuilt.key, shipped.key)
    # Half precision: the same computation rounds the same; another machine's last bits may not.
    np.testing.assert_allclose(rebuilt.trajectories, shipped.trajectories, rtol=1e-3, atol=1e-4)


def test_held_out_walks_get_the_walk_model_on_any_rig_and_waves_none(bandai2_dir):
    from expressive_mocap.skeletons import retarget, synthetic_walk
    from expressive_mocap.skeletons.canonical import carried_for

    models = shipped_models()
    first = models[0].load()
    for style in ("exhausted", "normal", "active"):
        walk = em.read_bvh(bandai2_dir / f"dataset-2_walk_{style}_020.bvh")  # take 20: held out
        assert choose(walk, models)[0].action == "walk"
        on_cmu = retarget(walk, synthetic_walk("cmu").motion)  # as `exaggerate` carries another rig's file
        assert choose(carried_for(on_cmu, first).body, models)[0].action == "walk"
    wave = em.read_bvh(bandai2_dir / "dataset-2_wave-left-hand_normal_020.bvh")
    with pytest.raises(em.errors.MocapError, match="no shipped model fits") as refused:
        choose(wave, models)
    assert "name its --action" in str(refused.value)
    # With the action named (--action walk), the walk model still refuses a wave: the hint is --model only.
    with pytest.raises(em.errors.MocapError, match="no shipped model fits") as refused:
        choose(wave, [m for m in models if m.action == "walk"], explicit=True)
    assert "--action" not in str(refused.value) and "--model" in str(refused.value)


def test_the_signature_tells_runs_from_walks_and_waves_from_raises(bandai2_dir):
    """Flight (no foot down) is a run's, repeated strokes a wave's: what the fit alone confused
    (a right-hand wave fitted the right-hand raise model; slow runs the walks model)."""

    def found(action: str, style: str) -> dict[str, float]:
        return signature(em.read_bvh(bandai2_dir / f"dataset-2_{action}_{style}_020.bvh"))  # held out

    for style in ("exhausted", "normal", "active"):
        assert found("walk", style)["flight"] <= SIGNATURE_MARGINS["flight"]
        assert found("raise-up-right-hand", style)["repeats"] <= SIGNATURE_MARGINS["repeats"]
        assert found("wave-right-hand", style)["repeats"] >= 2 * SIGNATURE_MARGINS["repeats"]
    assert found("run", "normal")["flight"] >= 0.2 and found("run", "active")["flight"] >= 0.2


def test_held_out_takes_get_their_own_action_or_none(bandai2_dir):
    """Every shipped action's held-out takes (take 20 of each style) get a model of that action;
    a run, a wave or a raise, whose actions ship no model, is refused, not edited by a walk's or
    another gesture's model."""
    models = shipped_models()
    shipped = {m.action: m for m in models}
    for action, model in shipped.items():
        for style in model.styles:
            take = em.read_bvh(bandai2_dir / f"dataset-2_{action}_{style}_020.bvh")
            assert choose(take, models)[0].action == action, (action, style)
    for other in sorted(set(ACTIONS) - set(shipped)):
        with pytest.raises(em.errors.MocapError, match="no shipped model fits"):
            choose(em.read_bvh(bandai2_dir / f"dataset-2_{other}_normal_020.bvh"), models)
