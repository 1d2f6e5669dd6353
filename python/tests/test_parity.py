"""s2kf.track and `s2kf track` are two front ends of one tracking request (include/s2kf/app/
track_request.hpp): every option of the program is a keyword of s2kf.track (dashes as underscores)
with the same default, but for the program's own options listed below; and both give the same
numbers on a bundled recording."""
import json
import re
import subprocess

import numpy as np
import s2kf

# Options only the program has, and why.
PROGRAM_ONLY = {
    # files: Python returns a TrackResult and writes with its write()/to_* methods
    "out", "formats", "bvh_units", "derivatives", "mass", "figure", "html",
    # a batch of recordings: Python calls track() per recording
    "jobs", "shard", "dry_run",
    # printing and pacing on a terminal
    "quiet", "verbose", "realtime",
    "help",
}


# One option line of CLI11's help: "  --samples INT:INT in [3 - 100001]=301", "  --gain TEXT=information-form",
# "  --markerset TEXT" (no default), "  --smooth" (a flag), "  --no-calibrate{false}" (a negated flag).
OPTION = re.compile(r"^\s+(?:-\w,)?--(?P<name>[a-z][a-z0-9-]*)(?P<negated>\{false\})?"
                    r"(?: (?P<type>[A-Z]+(?::\{[^}]*\}|:[A-Z]+(?: in \[[^\]]*\])?)?)(?:=(?P<default>\S*))?)?")


def program_options(cli_path):
    """{keyword: default text, None when none, or a bool for a flag} from `s2kf track --help`; a flag
    `--x` reads as x=False and a negated flag `--no-x` as x=True (Python keeps the positive name)."""
    text = subprocess.run([cli_path, "track", "--help"], capture_output=True, text=True, check=True).stdout
    options = {}
    for line in text.splitlines():
        m = OPTION.match(line)
        if not m:
            continue
        name = m.group("name")
        if m.group("type") is None:  # a flag
            key, value = (name[3:], True) if name.startswith("no-") else (name, False)
        else:
            key, value = name, m.group("default")
        options[key.replace("-", "_")] = value
    return options


def test_the_help_is_read_as_written():
    """The parser above on the forms CLI11 writes (a parser that reads nothing would pass the test below)."""
    assert OPTION.match("  --height FLOAT:FLOAT in [300 - 3000]=0").group("default") == "0"
    assert OPTION.match("  --preset TEXT:{default,paper}=default").group("default") == "default"
    assert OPTION.match("  --figure INT:NONNEGATIVE=-1 draw frame").group("default") == "-1"
    assert OPTION.match("  --markerset TEXT            bundled").group("default") is None
    assert OPTION.match("  --no-calibrate{false}       track").group("type") is None


def same_default(program, python):
    if isinstance(program, bool) or python is None or isinstance(python, bool):
        return program == python or (program is None and python in (None, ""))
    if isinstance(python, (int, float)):
        return program is not None and float(program) == float(python)
    return program == python


def test_every_program_option_is_a_keyword_with_the_same_default(cli):
    cli_path = cli.path
    options = program_options(cli_path)
    assert {"samples", "gain", "calibrate", "uniform_noise", "smooth", "out"} <= options.keys(), options
    python = python_keywords()
    missing = sorted(k for k in options if k not in PROGRAM_ONLY and k not in python)
    assert not missing, f"s2kf track options without an s2kf.track keyword: {missing}"
    different = {k: (options[k], python[k]) for k in options
                 if k not in PROGRAM_ONLY and not same_default(options[k], python[k])}
    assert not different, f"defaults differ (program, Python): {different}"
    stale = sorted(k for k in PROGRAM_ONLY - {"help"} if k not in options)
    assert not stale, f"listed as program-only but not options of s2kf track: {stale}"


def python_keywords():
    """{keyword: default} of s2kf.track, read from its pybind11 signature line."""
    signature = s2kf.track.__doc__.splitlines()[0]
    keywords = {}
    for name, value in re.findall(r"(\w+): [^=,()]+(?:\[[^\]]*\])? = ([^,)]+)", signature):
        value = value.strip()
        if value == "None":
            keywords[name] = None
        elif value in ("True", "False"):
            keywords[name] = value == "True"
        elif re.match(r"^-?[\d.e+-]+$", value):
            keywords[name] = float(value)
        else:
            keywords[name] = value.strip("'")
    keywords["static"] = None  # `static` is a keyword of Python
    return keywords


def test_the_parser_fails_on_a_missing_keyword_or_default():
    """The comparison above must be able to fail."""
    assert not same_default("301", 101)
    assert not same_default("information-form", "square-root")
    assert not same_default(False, True)
    assert same_default(None, None) and same_default("0.03", 0.03) and same_default(True, True)


def test_both_give_the_same_joint_angles_on_the_walk(cli, tmp_path, data_dir):
    walk = data_dir / "walk.c3d"
    cli("track", walk, "--out", tmp_path / "cli", "--quiet", "--formats", "csv")
    result = s2kf.track(str(walk))
    result.to_csv(str(tmp_path / "py.csv"))
    ours = np.genfromtxt(tmp_path / "py.csv", delimiter=",", names=True)
    theirs = np.genfromtxt(tmp_path / "cli.csv", delimiter=",", names=True)
    assert ours.dtype.names == theirs.dtype.names and len(ours) == len(theirs) == 551
    for column in ours.dtype.names[8:]:  # the 40 joint angles (after frame, time and the root)
        np.testing.assert_allclose(ours[column], theirs[column], rtol=0, atol=1e-9, err_msg=column)
    assert np.isfinite(result.joints[100:]).all()


def test_both_place_the_labels_the_set_does_not_name(cli, tmp_path, data_dir):
    """The walk with three labels renamed: the program and s2kf.track both place the three by their
    motion on the same segments and give the same joint angles (the marker-set choice is shared)."""
    labels, rate, points = s2kf.read_c3d(str(data_dir / "walk.c3d"))
    renamed = {"LKNE": "KneeLat_L", "RTIP": "ShankR2", "LAEL": "ElbowL"}
    recording = tmp_path / "walk_renamed.c3d"
    s2kf.write_c3d(str(recording), [renamed.get(label, label) for label in labels], rate, points)
    cli("track", recording, "--out", tmp_path / "cli", "--quiet", "--formats", "csv", "--samples", "101",
        "--no-calibrate")
    result = s2kf.track(str(recording), samples=101, calibrate=False)
    result.to_csv(str(tmp_path / "py.csv"))
    with open(tmp_path / "cli.json") as f:
        program = json.load(f)
    placed = {m["label"]: m["segment"] for m in result.summary["markers_inferred"]}
    assert set(placed) == set(renamed.values()), result.summary["markers_inferred"]
    assert placed == {m["label"]: m["segment"] for m in program["markers_inferred"]}
    ours = np.genfromtxt(tmp_path / "py.csv", delimiter=",", names=True)
    theirs = np.genfromtxt(tmp_path / "cli.csv", delimiter=",", names=True)
    for column in ours.dtype.names[8:]:
        np.testing.assert_allclose(ours[column], theirs[column], rtol=0, atol=1e-9, err_msg=column)
    assert (tmp_path / "cli_markerset.json").exists() and not (tmp_path / "py_markerset.json").exists()
