"""simulate: the same recording as `s2kf simulate` for the same settings and seed, truth included,
and a truth that explains the clean markers through the body model."""
import csv

import numpy as np
import pytest

import s2kf


def test_equals_the_program_for_the_same_seed(cli, tmp_path):
    out = tmp_path / "walk.c3d"
    cli("simulate", "--motion", "walk", "--seed", 3, "--frames", 60, "--occlusion", "0.02,10",
        "--height", 1650, "--out", out)
    sim = s2kf.simulate("walk", seed=3, frames=60, occlusion=(0.02, 10), height_mm=1650)
    labels, rate, points = s2kf.read_c3d(str(out))
    assert labels == sim.labels and rate == sim.rate
    assert (np.isnan(points) == np.isnan(sim.points)).all() and np.isnan(points).any()
    assert (sim.visible == ~np.isnan(sim.points).any(axis=2)).all()
    # The C3D file holds float32.
    np.testing.assert_array_equal(points, sim.points.astype(np.float32).astype(np.float64))
    with open(tmp_path / "walk_truth.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0][2:] == s2kf.pose_columns(s2kf.BodyModel())
    truth = np.array([[float(v) for v in row[2:]] for row in rows[1:]])
    np.testing.assert_allclose(sim.truth, truth, rtol=1e-8, atol=1e-9)
    clean = np.loadtxt(tmp_path / "walk_clean.csv", delimiter=",", skiprows=1)[:, 2:].reshape(60, 50, 3)
    np.testing.assert_allclose(sim.clean, clean, rtol=1e-8, atol=1e-6)


def test_without_placement_soft_tissue_or_scale_error_the_truth_gives_the_clean_markers():
    sim = s2kf.simulate("handstand", frames=30, placement_mm=0, soft_tissue_mm=0, segment_scale_sd=0,
                        height_mm=1750)
    model = s2kf.BodyModel(1750)
    np.testing.assert_allclose(model.marker_positions(sim.truth), sim.clean, atol=1e-9)
    # and the measured markers are the clean ones plus about 0.7 mm of noise per coordinate
    assert np.std(sim.points - sim.clean) == pytest.approx(0.7, rel=0.1)


def test_unknown_motions_and_bad_settings_are_value_errors():
    assert "walk" in s2kf.motions()
    with pytest.raises(ValueError, match="unknown motion 'moonwalk' \\(known: .*walk"):
        s2kf.simulate("moonwalk")
    with pytest.raises(ValueError, match="height_mm must lie between 500 and 2500, got 90"):
        s2kf.simulate("walk", height_mm=90)
    with pytest.raises(ValueError):
        s2kf.simulate("walk", dropouts=[("NOPE", 0.0, 1.0)])
