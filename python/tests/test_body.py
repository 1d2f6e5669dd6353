"""BodyModel and forward kinematics: batch results against the command-line program's
`s2kf model --pose`, and against the rigid motion of the root done by hand."""
import csv
import io
import json

import numpy as np
import pytest

import s2kf


def program_markers(cli, tmp_path, height, root_position, root_rpy, joints):
    pose = {"root_position": list(root_position), "root_rpy": list(root_rpy), "joints": joints}
    path = tmp_path / "pose.json"
    path.write_text(json.dumps(pose))
    rows = list(csv.DictReader(io.StringIO(cli("model", "--height", height, "--pose", path))))
    return [r["marker"] for r in rows], np.array([[float(r[a]) for a in "xyz"] for r in rows])


def test_model_tables():
    model = s2kf.BodyModel(1800)
    assert model.joint_count == 40 and model.marker_count == 50 and model.height_mm == 1800
    assert model.joint_names[:3] == ["BPx", "BPz", "BPy"]
    assert (model.lower_limits <= model.upper_limits).all()
    assert s2kf.pose_columns(model)[:7] == ["root_x", "root_y", "root_z", "root_roll", "root_pitch", "root_yaw", "BPx"]
    np.testing.assert_allclose(model.scaled(900).marker_offsets, model.marker_offsets / 2, rtol=1e-15)


def test_batch_equals_the_program_pose_by_pose(cli, tmp_path):
    model = s2kf.BodyModel(1800)
    rng = np.random.default_rng(7)
    poses = np.zeros((3, 46))
    poses[:, :3] = rng.uniform(-500, 500, (3, 3))
    poses[:, 3:6] = rng.uniform(-1.5, 1.5, (3, 3))
    poses[:, 6:] = rng.uniform(model.lower_limits, model.upper_limits, (3, 40))
    batch = model.marker_positions(poses)
    assert batch.shape == (3, 50, 3)
    for pose, markers in zip(poses, batch):
        joints = dict(zip(model.joint_names, pose[6:].tolist()))
        names, expected = program_markers(cli, tmp_path, 1800, pose[:3], pose[3:6], joints)
        assert names == model.marker_names
        np.testing.assert_allclose(markers, expected, atol=1e-6)  # the program prints 6 decimals
        np.testing.assert_allclose(model.marker_positions(pose), markers, atol=1e-9)


def test_root_motion_moves_every_marker_rigidly():
    """R = Rz(yaw) Ry(pitch) Rx(roll) and a translation, built here from the definitions."""
    model = s2kf.BodyModel()
    rng = np.random.default_rng(11)
    joints = rng.uniform(model.lower_limits, model.upper_limits)
    still = model.marker_positions(np.concatenate([np.zeros(6), joints]))
    roll, pitch, yaw = 0.3, -0.7, 2.1
    t = np.array([100.0, -250.0, 900.0])
    c, s = np.cos, np.sin
    rx = np.array([[1, 0, 0], [0, c(roll), -s(roll)], [0, s(roll), c(roll)]])
    ry = np.array([[c(pitch), 0, s(pitch)], [0, 1, 0], [-s(pitch), 0, c(pitch)]])
    rz = np.array([[c(yaw), -s(yaw), 0], [s(yaw), c(yaw), 0], [0, 0, 1]])
    moved = model.marker_positions(np.concatenate([t, [roll, pitch, yaw], joints]))
    np.testing.assert_allclose(moved, still @ (rz @ ry @ rx).T + t, atol=1e-9)


def test_many_poses_in_blocks_equal_one_at_a_time():
    model = s2kf.BodyModel()
    rng = np.random.default_rng(5)
    poses = np.concatenate([rng.normal(0, 300, (200, 3)), rng.normal(0, 1, (200, 3)),
                            rng.uniform(model.lower_limits, model.upper_limits, (200, 40))], axis=1)
    batch = model.marker_positions(poses)
    for k in (0, 63, 64, 65, 199):  # block edges of the kernel (64 poses)
        np.testing.assert_allclose(batch[k], model.marker_positions(poses[k]), atol=1e-9)


@pytest.mark.parametrize("poses", [np.zeros(45), np.zeros((2, 47)), np.zeros((2, 46, 1))])
def test_wrong_pose_shapes_are_value_errors(poses):
    with pytest.raises(ValueError, match=r"poses must have shape \(46,\) or \(F, 46\), got"):
        s2kf.BodyModel().marker_positions(poses)


def test_a_body_needs_a_positive_height():
    with pytest.raises(ValueError, match="the body height must be a positive number of mm"):
        s2kf.BodyModel(-3)
