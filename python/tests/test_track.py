"""s2kf.track against the command-line program: the same files byte for byte and the same summary
(but for the timing) on the bundled recordings; the streaming Tracker of a result reproduces its
motion exactly; bad inputs are Python errors with the program's sentences."""
import json

import numpy as np
import pytest

import s2kf

OUTPUTS = (".csv", ".mot", ".bvh", "_markers.csv")


def same_as_program(cli, tmp_path, result, program_arguments, known_differences=()):
    """The files `s2kf track` writes and the module writes for the same recording are the same;
    `known_differences` names summary keys compared by the caller instead (returned)."""
    cli("track", *program_arguments, "--out", tmp_path / "cli", "--quiet")
    result.write(str(tmp_path / "py"))
    for suffix in OUTPUTS:
        ours, theirs = (tmp_path / f"py{suffix}").read_bytes(), (tmp_path / f"cli{suffix}").read_bytes()
        assert ours == theirs, f"{suffix} differs from the program's"
    ours, theirs = (json.loads((tmp_path / f"{who}.json").read_text()) for who in ("py", "cli"))
    assert ours == result.summary
    for summary in (ours, theirs):
        assert summary.pop("latency_ms").keys() == {"median", "p99"}  # timings differ run to run
        assert summary.pop("seconds_per_stage").keys() == {
            "read", "marker_set", "height", "calibration", "tracking", "smoothing", "writing"}
    set_aside = {key: (ours.pop(key), theirs.pop(key)) for key in known_differences}
    assert ours == theirs
    return set_aside


@pytest.fixture(scope="module")
def handstand_300(data_dir):
    """The handstand with the defaults but a 300-frame calibration: what three tests compare with."""
    return s2kf.track(str(data_dir / "handstand.c3d"), calibration_frames=300)


def test_handstand_as_the_program_tracks_it(cli, tmp_path, data_dir):
    path = str(data_dir / "handstand.c3d")
    result = s2kf.track(path)
    same_as_program(cli, tmp_path, result, [path])
    summary = result.summary
    assert summary["marker_set"] == "kit" and summary["calibration"] is not None
    assert summary["calibration"]["weak_direction_shrink"] == 0.03  # the default, recorded
    assert summary["frames_tracked"] == 675 and result.poses.shape == (675, 46)
    assert np.isfinite(result.joints).all()
    np.testing.assert_array_equal(result.poses[:, :3], result.root_position)
    np.testing.assert_array_equal(result.poses[:, 6:], result.joints)
    # The mean marker distance is that of the model's markers at the tracked poses.
    rec = s2kf.read_c3d(path)
    predicted = result.model.marker_positions(result.poses)
    distance = np.linalg.norm(rec.points - predicted, axis=2).mean(axis=1)
    np.testing.assert_allclose(result.marker_distance, distance, rtol=1e-9)


def test_calibration_shrink_as_the_program_takes_it(cli, tmp_path, data_dir, handstand_300):
    path = str(data_dir / "handstand.c3d")
    result = s2kf.track(path, calibration_shrink=0.0, calibration_frames=300)
    same_as_program(cli, tmp_path, result, [path, "--calibration-shrink", "0", "--calibration-frames", "300"])
    assert result.summary["calibration"]["weak_direction_shrink"] == 0.0
    shrunk = handstand_300
    assert shrunk.summary["calibration"]["segment_scale"] != result.summary["calibration"]["segment_scale"]


def test_uniform_noise_as_the_program_takes_it(cli, tmp_path, data_dir, handstand_300):
    """Each marker's noise follows its calibration residual unless uniform_noise is set."""
    path = str(data_dir / "handstand.c3d")
    uniform = s2kf.track(path, calibration_frames=300, uniform_noise=True)
    same_as_program(cli, tmp_path, uniform, [path, "--calibration-frames", "300", "--uniform-noise"])
    assert uniform.summary["calibration"]["marker_noise_mm"] == {}
    default = handstand_300
    noise = default.summary["calibration"]["marker_noise_mm"]
    assert len(noise) >= 30 and all(5.0 <= sd <= 20.0 for sd in noise.values())
    assert not np.array_equal(default.poses, uniform.poses)


def test_points_in_memory_give_the_files_of_the_program(cli, tmp_path, data_dir):
    """Arrays, not a file: the same motion (only the summary's input name differs)."""
    labels, rate, points = s2kf.read_c3d(str(data_dir / "walk.c3d"))
    result = s2kf.track(points.copy(), labels, rate, calibrate=False, smooth=True, name="walk")
    cli("track", data_dir / "walk.c3d", "--no-calibrate", "--smooth", "--out", tmp_path / "cli", "--quiet")
    result.to_csv(str(tmp_path / "py.csv"))
    result.to_mot(str(tmp_path / "py.mot"))
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    assert (tmp_path / "py.mot").read_bytes() == (tmp_path / "cli.mot").read_bytes()
    assert result.summary["smoothed"] and result.summary["calibration"] is None


def test_plug_in_gait_with_model_outputs_as_the_program(cli, tmp_path, c3d_dir):
    path = str(c3d_dir / "PiG_Motion-FlatFoot-One.c3d")
    result = s2kf.track(path, samples=101)
    same_as_program(cli, tmp_path, result, [path, "--samples", 101])
    assert result.summary["marker_set"] == "plugin_gait"
    rec = s2kf.read_c3d(path)
    assert rec.model_output.sum() == 80
    # Each model output is listed under its own name, in file order (the program does the same).
    outputs = [label for label, output in zip(rec.raw_labels, rec.model_output) if output]
    assert len(set(outputs)) == 80
    assert [label for label in result.summary["labels_ignored"] if label in outputs] == outputs
    # The same from read_c3d's arrays: model outputs are flagged and never matched.
    again = s2kf.track(rec, samples=101)
    np.testing.assert_array_equal(again.poses, result.poses)
    assert again.summary["labels_ignored"] == result.summary["labels_ignored"]


def test_the_gain_as_the_program_takes_it(cli, tmp_path, data_dir, handstand_300):
    """gain='square-root' is the exact update (`s2kf track --gain square-root`): other poses than the
    default information form, recorded in the summary; the streaming Tracker takes it too."""
    path = str(data_dir / "handstand.c3d")
    exact = s2kf.track(path, calibration_frames=300, gain="square-root")
    same_as_program(cli, tmp_path, exact, [path, "--calibration-frames", "300", "--gain", "square-root"])
    assert exact.summary["gain"] == "square-root"
    default = handstand_300
    assert default.summary["gain"] == "information-form"
    assert not np.array_equal(default.poses, exact.poses)
    rec = s2kf.read_c3d(path)
    streaming = s2kf.Tracker(rec.labels, rec.rate, samples=101, gain="square-root")
    informed = s2kf.Tracker(rec.labels, rec.rate, samples=101)
    frames = rec.points[:50]
    last = [[t.process(frame).pose for frame in frames][-1] for t in (streaming, informed)]
    assert not np.array_equal(last[0], last[1])


def test_streaming_the_frames_reproduces_the_motion(data_dir):
    rec = s2kf.read_c3d(str(data_dir / "handstand_occluded.c3d"))
    result = s2kf.track(rec, samples=101)
    tracker = result.tracker()
    poses = np.array([tracker.process(frame, visible).pose for frame, visible in zip(rec.points, rec.visible)])
    np.testing.assert_array_equal(poses, result.poses)


def test_a_known_marker_set_can_be_forced(data_dir):
    """The given set is used, and the labels it does not name (the model's other markers) are placed by
    their motion, as `s2kf track --markerset` does (docs/marker-sets.md)."""
    result = s2kf.track(str(data_dir / "handstand.c3d"), markerset="plugin_gait", calibrate=False, samples=101)
    assert result.summary["marker_set"] == "plugin_gait+inferred"
    assert result.summary["marker_set_source"].startswith("given; with ")
    assert len(result.summary["markers_inferred"]) > 0


def test_a_recording_of_no_whole_body_is_refused_in_python_words(cli, tmp_path):
    """Ten markers on the head and four on the shoulders, labels no set names (as the program's test
    ARecordingOfNoWholeBodyIsRefusedUnlessForced): refused, and the sentence names the keywords that
    give a set or force it, not the program's options."""
    face = tmp_path / "face.json"
    like = ["LFHD", "RFHD", "LBHD", "RBHD"]
    markers = [{"label": f"F{i}", "like": like[i]} for i in range(4)]
    offsets = [("LFHD", [30, 15, -30]), ("LFHD", [-5, 5, -50]), ("RFHD", [5, 5, -50]), ("LFHD", [30, 25, -70]),
               ("LFHD", [-15, -40, -30]), ("RFHD", [15, -40, -30])]
    markers += [{"label": f"F{4 + i}", "like": m, "offset": o} for i, (m, o) in enumerate(offsets)]
    markers += [{"label": f"T{i}", "like": m} for i, m in enumerate(["C7", "CLAV", "LSHO", "RSHO"])]
    face.write_text(json.dumps({"name": "face", "reference_height_mm": 1000, "markers": markers}))
    recording = tmp_path / "face.c3d"
    cli("simulate", "--motion", "random_sweep", "--frames", 400, "--seed", 5, "--markerset", face, "--out", recording)
    with pytest.raises(ValueError, match=r"does not look like a whole body.*\(give a marker set with markerset=\.\.\., "
                                         r"or track it anyway with force=True\)$") as refused:
        s2kf.track(str(recording), samples=101)
    assert "--" not in str(refused.value)


def test_bad_recordings_are_python_errors(tmp_path, data_dir):
    labels, rate, points = s2kf.read_c3d(str(data_dir / "walk.c3d"))
    with pytest.raises(ValueError, match=r"points must have shape \(F, P, 3\) with P = 50 labels, got \(551, 50\)"):
        s2kf.track(points[:, :, 0], labels, rate)
    with pytest.raises(ValueError, match="labels and rate are needed"):
        s2kf.track(points)
    with pytest.raises(ValueError, match="^recording: no frame has the 8 visible markers needed to start tracking$"):
        s2kf.track(np.full_like(points, np.nan), labels, rate, calibrate=False, samples=101)
    with pytest.raises(ValueError, match="the coordinates are not in millimetres"):
        s2kf.track(points * 1e6, labels, rate, calibrate=False, height_mm=1750, samples=101)
    with pytest.raises(ValueError, match="none of the recording's labels belongs to a bundled marker set"):
        s2kf.track(points, [f"X{i}" for i in range(50)], rate)
    with pytest.raises(ValueError, match=r"unknown marker set 'nope' \(bundled: anatomical_landmarks, cmu, kit"):
        s2kf.track(points, labels, rate, markerset="nope")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        s2kf.track(points, labels, rate, markerset=str(tmp_path / "mine.json"))
    with pytest.raises(ValueError, match="the frame rate must be a positive number of Hz"):
        s2kf.track(points, labels, -1.0)
    with pytest.raises(ValueError, match=r"calibration_shrink must lie in \[0, 1e6\]"):
        s2kf.track(points, labels, rate, calibration_shrink=-1.0)
    with pytest.raises(ValueError, match="method must be 's2kf' or 'baseline'"):
        s2kf.track(points, labels, rate, method="ukf")
    with pytest.raises(ValueError, match=r"unknown gain 'kalman' \(use 'information-form' or 'square-root'\)"):
        s2kf.track(points, labels, rate, gain="kalman")
    with pytest.raises(ValueError, match="unknown gain 'kalman'"):
        s2kf.Tracker(labels, rate, gain="kalman")
    with pytest.raises(ValueError, match="the gain 'information-form-root-products' was removed: .* use 'square-root'"):
        s2kf.track(points, labels, rate, gain="information-form-root-products")


def test_bad_files_are_os_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        s2kf.track(str(tmp_path / "missing.c3d"))
    (tmp_path / "text.c3d").write_text("not a recording at all, just words\n" * 20)
    with pytest.raises(OSError, match="text.c3d: not a C3D file"):
        s2kf.track(str(tmp_path / "text.c3d"))


def test_a_static_trial_alone_calibrates_the_subject_first(cli, tmp_path):
    """static= with static_alone=True does what `s2kf calibrate --static` and then subject= do, in one call."""
    static, walk = tmp_path / "static.c3d", tmp_path / "walk.c3d"
    cli("simulate", "--motion", "static", "--seed", "5", "--out", static)
    cli("simulate", "--motion", "walk", "--seed", "5", "--frames", "150", "--out", walk)
    cli("calibrate", static, "--static", "--quiet", "--out", tmp_path / "subject.json")
    one_step = s2kf.track(str(walk), static=str(static), static_alone=True)
    two_steps = s2kf.track(str(walk), subject=str(tmp_path / "subject.json"))
    np.testing.assert_array_equal(one_step.poses, two_steps.poses)
    assert one_step.summary["marker_set_source"] == f"calibrated on the static trial {static}"
    assert one_step.summary["calibration"] is None  # the recording itself is not calibrated on
    with pytest.raises(ValueError, match="give static or subject, not both"):
        s2kf.track(str(walk), static=str(static), subject=str(tmp_path / "subject.json"))
    with pytest.raises(FileNotFoundError, match="^static: missing.c3d: cannot open the file"):
        s2kf.track(str(walk), static=str(tmp_path / "missing.c3d"))
    with pytest.raises(ValueError, match="static_sd must lie between"):
        s2kf.track(str(walk), static=str(static), static_sd=0)


def test_the_static_keywords_are_the_programs(cli, tmp_path):
    """static (with the recording), static_alone, static_stretch, static_pose and static_posture do what
    the program's options do; static_refine, deprecated, says what replaced it."""
    static, walk = tmp_path / "static.c3d", tmp_path / "walk.c3d"
    cli("simulate", "--motion", "static", "--seed", "5", "--out", static)
    cli("simulate", "--motion", "walk", "--seed", "5", "--frames", "150", "--out", walk)
    # The static trial and the walk calibrated together, as `s2kf track --static`.
    refined = s2kf.track(str(walk), static=str(static))
    cli("track", walk, "--static", static, "--quiet", "--formats", "csv", "--out", tmp_path / "cli")
    refined.to_csv(str(tmp_path / "py.csv"))  # both as written (9 digits)
    ours, theirs = (np.genfromtxt(tmp_path / f"{n}.csv", delimiter=",", skip_header=1) for n in ("py", "cli"))
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9)
    alone = s2kf.track(str(walk), static=str(static), static_alone=True)  # the comparison can fail
    assert np.nanmax(np.abs(alone.joints - refined.joints)) > 1e-3
    assert refined.summary["calibration"] is not None
    assert alone.summary["calibration"] is None
    with pytest.warns(DeprecationWarning, match="static_refine is deprecated: .* is what static does now"):
        deprecated = s2kf.track(str(walk), static=str(static), static_refine=True)
    np.testing.assert_array_equal(deprecated.joints, refined.joints)
    # The still recording is its own static trial unless static_stretch=False.
    still = s2kf.track(str(static), static_pose="zero")
    assert any("are a static trial in the zero pose" in m for m in still.summary["marker_set_messages"])
    plain = s2kf.track(str(static), static_stretch=False)
    assert not any("static trial" in m for m in plain.summary["marker_set_messages"])
    with pytest.raises(ValueError, match="static_alone calibrates the subject on the static trial alone; it needs static"):
        s2kf.track(str(walk), static_alone=True)
    with pytest.raises(ValueError, match="static_posture must be 'auto', 'near' or 'exact'"):
        s2kf.track(str(walk), static=str(static), static_posture="close")
    with pytest.raises(ValueError, match="static_pose: 'y-pose' is neither zero, t-pose, a-pose"):
        s2kf.calibrate(static, static=True, static_pose="y-pose")


def test_calibrate_writes_the_subject_file_the_program_writes(cli, tmp_path):
    """s2kf.calibrate is `s2kf calibrate`: the same subject file (but for its name), also returned."""
    static = tmp_path / "static.c3d"
    cli("simulate", "--motion", "static", "--seed", "6", "--out", static)
    cli("calibrate", static, "--static", "--quiet", "--out", tmp_path / "cli.json")
    subject = s2kf.calibrate(static, static=True, out=tmp_path / "py.json")
    written = json.loads((tmp_path / "py.json").read_text())
    program = json.loads((tmp_path / "cli.json").read_text())
    assert subject == written
    assert written.pop("name") == "py" and program.pop("name") == "cli"
    assert written == program
    free = s2kf.calibrate(static)  # without the posture: other offsets
    assert max(max(abs(a - b) for a, b in zip(m["offset"], n["offset"]))
               for m, n in zip(free["markers"], subject["markers"])) > 1.0
    with pytest.raises(FileNotFoundError, match="no such file"):
        s2kf.calibrate(tmp_path / "missing.c3d")
    with pytest.raises(ValueError, match="static_sd must lie between"):
        s2kf.calibrate(static, static=True, static_sd=100)
