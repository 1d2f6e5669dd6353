"""read_c3d and write_c3d: the real files of tests/data/c3d against their independent reference
values (expected.json), write/read round trips, and the errors for files that are not C3D."""
import json

import numpy as np
import pytest

import s2kf


def reference_entries(c3d_dir):
    return json.loads((c3d_dir / "expected.json").read_text())


def test_real_files_match_the_independent_reference(c3d_dir):
    checked = 0
    for entry in reference_entries(c3d_dir):
        path = c3d_dir / entry["file"]
        if "error" in entry:
            with pytest.raises(OSError):
                s2kf.read_c3d(str(path))
            continue
        rec = s2kf.read_c3d(str(path))
        assert rec.points.shape == (entry["frames"], entry["points"], 3)
        assert rec.rate == pytest.approx(entry["rate"], rel=1e-9)
        labels = entry["labels"]
        assert rec.raw_labels == [labels[i] if i < len(labels) else "" for i in range(entry["points"])]
        # A missing point is NaN in every coordinate and flagged invisible; a visible one is finite.
        nan = np.isnan(rec.points)
        assert (nan.all(axis=2) == ~rec.visible).all() and (nan.any(axis=2) == ~rec.visible).all()
        for sample in entry.get("samples", []):
            f, p = sample["frame_index"], sample["point_index"]
            if sample["fourth_word"] < 0:
                assert not rec.visible[f, p]
                continue
            stored = rec.points[f, p] / rec.to_mm  # reference values: the file's units, 4 decimals
            np.testing.assert_allclose(stored, [sample["x"], sample["y"], sample["z"]], atol=6e-5)
            checked += 1
    assert checked > 50


def test_unpacks_as_labels_rate_points_without_copying(data_dir):
    rec = s2kf.read_c3d(str(data_dir / "handstand.c3d"))
    labels, rate, points = rec
    assert labels[:3] == ["C7", "CLAV", "STRN"] and len(labels) == 50
    assert rate == 100.0
    assert points.shape == (675, 50, 3) and points.dtype == np.float64 and points.flags.c_contiguous
    # A view of the reader's own storage: two reads of the property share memory.
    assert np.shares_memory(points, rec.points)


def test_write_then_read_gives_the_same_points(tmp_path):
    rng = np.random.default_rng(3)
    points = rng.uniform(-2000, 2000, size=(40, 7, 3))
    points[5, 2] = np.nan
    points[10:20, 6] = np.nan
    labels = [f"M{i}" for i in range(7)]
    path = tmp_path / "round.c3d"
    s2kf.write_c3d(str(path), labels, 240.0, points)
    back_labels, rate, back = s2kf.read_c3d(str(path))
    assert back_labels == labels and rate == 240.0
    assert (np.isnan(back) == np.isnan(points)).all()
    # The writer stores float32: equal to float32 rounding.
    np.testing.assert_array_equal(back[~np.isnan(back)], points.astype(np.float32)[~np.isnan(points)])


def test_written_file_equals_the_programs_for_the_same_recording(tmp_path, data_dir, cli):
    """Reading the occluded handstand and writing it again: the program reads back the same points."""
    labels, rate, points = s2kf.read_c3d(str(data_dir / "handstand_occluded.c3d"))
    path = tmp_path / "again.c3d"
    s2kf.write_c3d(str(path), labels, rate, points)
    ours = json.loads(cli("c3d", path, "--json"))
    theirs = json.loads(cli("c3d", data_dir / "handstand_occluded.c3d", "--json"))
    for key in ("frames", "labels", "missing", "rate", "points"):
        assert ours[key] == theirs[key], key
    np.testing.assert_array_equal(s2kf.read_c3d(str(path)).points, points)


def test_a_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.c3d: cannot open the file"):
        s2kf.read_c3d(str(tmp_path / "nothing.c3d"))


def test_a_text_file_is_not_c3d(tmp_path):
    path = tmp_path / "notes.c3d"
    path.write_text("these are not markers\n" * 40)
    with pytest.raises(OSError, match=r"^notes.c3d: not a C3D file: byte 1 is 0x68, expected 0x50$"):
        s2kf.read_c3d(str(path))


def test_an_empty_file_is_not_c3d(c3d_dir):
    with pytest.raises(OSError, match="^Empty.c3d: not a C3D file: the file is empty$"):
        s2kf.read_c3d(str(c3d_dir / "Empty.c3d"))


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((4, 3, 3)), r"points must have shape \(F, P, 3\) with P = 2 labels, got \(4, 3, 3\)"),
        (np.zeros((4, 2)), r"points must have shape \(F, P, 3\) with P = 2 labels, got \(4, 2\)"),
        ("abc", "points must be an array of numbers"),
    ],
)
def test_write_rejects_points_of_the_wrong_shape(tmp_path, points, message):
    with pytest.raises(ValueError, match=message):
        s2kf.write_c3d(str(tmp_path / "x.c3d"), ["A", "B"], 100.0, points)
    assert not (tmp_path / "x.c3d").exists()


def test_write_rejects_a_bad_rate(tmp_path):
    with pytest.raises(ValueError, match="the frame rate must be a positive number of Hz"):
        s2kf.write_c3d(str(tmp_path / "x.c3d"), ["A"], float("nan"), np.zeros((1, 1, 3)))
