"""A body model's settings and training report as typed records: read from the file (older files
with entries missing, or entries a newer version added, included), written back as they were,
and refused with a ModelError naming an entry of the wrong kind."""

import io
import json
import re

import numpy as np
import pytest

from expressive_mocap.decoupling.body_model import BodyModel, poor_fit, shipped_model_bytes
from expressive_mocap.decoupling.records import BodyModelSettings, StageScores, TrainingReport
from expressive_mocap.decoupling.training import format_report
from expressive_mocap.errors import ModelError
from model_files import npz, small_models


def _meta(data: bytes) -> dict:
    return json.loads(str(np.load(io.BytesIO(data))["meta"]))


def _load(settings, report) -> BodyModel:
    arrays, meta = small_models()["body"]
    return BodyModel.load(npz(arrays, dict(meta, settings=settings, report=report)))


def test_the_shipped_model_reads_into_records_and_saves_to_the_same_bytes():
    model = BodyModel.load()
    assert isinstance(model.settings, BodyModelSettings) and isinstance(model.report, TrainingReport)
    assert model.settings.hidden == 300 and model.settings.neutral_clips == 145
    assert model.report.split is not None and model.report.split.test_groups == 46
    assert model.report.fine_tuned is not None and model.report.fine_tuned.iterations == 300
    assert list(model.report.stages()) == list(TrainingReport.STAGES)
    assert model.to_bytes() == shipped_model_bytes()
    assert _meta(model.to_bytes())["report"] == _meta(shipped_model_bytes())["report"]


def test_an_older_file_without_settings_or_report_loads_and_writes_them_back_empty():
    model = _load({}, {})
    assert model.settings == BodyModelSettings() and model.report == TrainingReport()
    assert model.settings.hidden is None and model.report.fine_tuned is None
    assert poor_fit(model.report) is None and "test MSE ?" in repr(model)
    assert _meta(model.to_bytes())["settings"] == {} and _meta(model.to_bytes())["report"] == {}


def test_missing_entries_are_none_and_unknown_ones_are_kept_in_their_place():
    settings = {"hidden": 8, "seed": 3, "optimiser": "adam"}  # a newer version's entry
    report = {
        "test_variance": 0.5,
        "mean_pose": {"train_mse": 0.4, "test_mse": 0.5},  # no variance explained, no seconds
        "fine_tuned": {"test_mse": 0.6, "test_variance_explained": -0.2, "lr": 0.01},
        "distilled": {"test_mse": 0.1},
    }
    with pytest.warns(UserWarning, match="a poor model: its held-out pose error 0.6 is no better"):
        model = _load(settings, report)
    assert (model.settings.hidden, model.settings.seed, model.settings.max_iter) == (8, 3, None)
    assert model.settings.extra == {"optimiser": "adam"}
    assert model.report.mean_pose == StageScores(train_mse=0.4, test_mse=0.5)
    assert model.report.split is None and model.report.extra == {"distilled": {"test_mse": 0.1}}
    assert model.report.fine_tuned is not None and model.report.fine_tuned.extra == {"lr": 0.01}
    meta = _meta(model.to_bytes())
    assert meta["settings"] == settings and meta["report"] == report
    # Read as before: a network no better than the mean pose is poor, whatever else is missing.
    assert poor_fit(model.report) == (
        "its held-out pose error 0.6 is no better than the mean training pose's 0.5 (test variance explained -0.20)"
    )
    table = format_report(model.report)
    assert re.search(r"^mean_pose +0\.4 +0\.5 +\? +0\.0$", table, re.M), table
    assert table.startswith("split: None, test variance 0.5\n")


@pytest.mark.parametrize(
    "settings, report, where",
    [
        ({"hidden": "300"}, {}, "settings.hidden must be an integer, got '300'"),
        ({"seed": 1.5}, {}, "settings.seed must be an integer, got 1.5"),
        ({"features": 3}, {}, "settings.features must be text, got 3"),
        ({}, {"fine_tuned": {"test_mse": "low"}}, "report.fine_tuned.test_mse must be a number"),
        ({}, {"fine_tuned": {"test_mse": True}}, "report.fine_tuned.test_mse must be a number"),
        ({}, {"split": [1, 2]}, "report.split must be a JSON object"),
        ({}, {"mean_pose": 0.1}, "report.mean_pose must be a JSON object"),
    ],
)
def test_an_entry_of_the_wrong_kind_is_a_model_error_naming_it(settings, report, where):
    with pytest.raises(ModelError, match=f"^<bytes>: the metadata's {re.escape(where)}"):
        _load(settings, report)


def test_records_built_in_code_write_what_training_writes():
    scores = StageScores(1e-3, 2e-3, 0.9, seconds=1.5, iterations=7)
    assert scores.to_json() == {
        "train_mse": 1e-3, "test_mse": 2e-3, "test_variance_explained": 0.9, "seconds": 1.5, "iterations": 7,
    }  # fmt: skip
    assert TrainingReport(test_variance=0.1, fine_tuned=scores).to_json() == {
        "test_variance": 0.1, "fine_tuned": scores.to_json(),
    }  # fmt: skip
    assert TrainingReport.from_json(TrainingReport(fine_tuned=scores).to_json()) == TrainingReport(fine_tuned=scores)
