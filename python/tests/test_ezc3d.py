"""s2kf's C3D reader against ezc3d, the reference C3D library (PyPI, python/requirements-test.txt):
every C3D file of the repository's test data (tests/data/c3d/*.c3d, data/*.c3d) is read by both, and
the labels, rate, first frame, units, point coordinates and missing samples agree. Where they differ
on purpose (a file ezc3d rejects or misreads), DIFFERENCES says why, and the test checks that ezc3d
still behaves so: when a new ezc3d reads such a file, the test fails and asks to compare it.

`python3 python/tests/test_ezc3d.py` prints the table of docs/c3d.md (with the module on PYTHONPATH).
"""
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import s2kf

# ezc3d is installed by scripts/python-env.sh; a missing one is a failure, not a skip.
import ezc3d

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]

# A difference on purpose: what ezc3d does with the file (an exception whose text contains
# `rejects`, or what `misreads` checks on the ezc3d object), why s2kf reads it otherwise, and the
# frames and points s2kf reads (`shape`) or its error (`s2kf_rejects`).
DIFFERENCES = {
    "Dance.c3d": dict(
        shape=(499, 40),
        rejects="OFFSET parameter is not an INT",
        why="ezc3d rejects the file (\"OFFSET parameter is not an INT\"); s2kf reads it: DATA_START 0 "
        "in the parameters (the header's word 9 is used), parameters beyond the declared block count, "
        "499 complete frames of the 500 declared",
    ),
    "Eb015sr.c3d": dict(
        shape=(450, 26),
        rejects="MIPS processor type not supported",
        why="ezc3d does not read MIPS (big-endian) files; s2kf reads the points of the Intel copy "
        "Eb015pi (which agrees) rounded to float32, as the file stores them",
    ),
    "MACsample.c3d": dict(
        shape=(180, 33),
        rejects="MIPS processor type not supported",
        why="ezc3d does not read MIPS (big-endian) files; s2kf reads it (integer storage, the "
        "header's scale where POINT:SCALE disagrees)",
    ),
    "Empty.c3d": dict(
        rejects="File is empty",
        s2kf_rejects="the file is empty",
        why="an empty file: both refuse it",
    ),
    "simple.c3d": dict(
        rejects="Could not read the processor type",
        s2kf_rejects="unknown processor type byte 0",
        why="processor byte 0: both refuse it",
    ),
    "bad_parameter_section.c3d": dict(
        shape=(332, 45),
        rejects="The format is not standard",
        why="the LABELS entry's offset-to-next points beyond the parameter section: ezc3d takes 12.6 GB "
        "of memory, then rejects the file (with ignore_bad_formatting=True it grew to 11.8 GB until the "
        "kernel killed it); s2kf ends that entry where its contents end, warns, and reads 332 frames of "
        "45 points",
    ),
    "phasespace_sample.c3d": dict(
        shape=(701, 40),
        misreads=lambda c: c["data"]["points"].shape[1:] == (0, 0),
        why="the file has no parameter section: ezc3d reads 0 points and 0 frames; s2kf takes 40 points, "
        "701 frames and 30 Hz from the header (labels point_1 to point_40, units assumed mm)",
    ),
}


# ezc3d reads the files it should reject in a child process with this much address space: it
# allocates 12.6 GB for bad_parameter_section.c3d before it rejects it, which here fails at once.
EZC3D_MEMORY_LIMIT = 4 << 30


def ezc3d_refusal(path):
    """ezc3d's error on `path` ("read" if it reads the file), from a child process whose address
    space is limited to EZC3D_MEMORY_LIMIT bytes."""
    child = (
        "import resource, sys\n"
        f"resource.setrlimit(resource.RLIMIT_AS, ({EZC3D_MEMORY_LIMIT}, {EZC3D_MEMORY_LIMIT}))\n"
        "import ezc3d\n"
        "try:\n    ezc3d.c3d(sys.argv[1])\nexcept Exception as error:\n    print(error)\nelse:\n    print('read')\n"
    )
    done = subprocess.run([sys.executable, "-c", child, str(path)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def c3d_files():
    return sorted((SOURCE_DIR / "tests" / "data" / "c3d").glob("*.c3d")) + sorted((SOURCE_DIR / "data").glob("*.c3d"))


def compare(path):
    """Reads `path` with both libraries and returns what agreed, as figures for the table; raises
    AssertionError naming the first quantity that differs."""
    theirs = ezc3d.c3d(str(path))
    ours = s2kf.read_c3d(str(path))
    header = theirs["header"]["points"]
    point = theirs["parameters"]["POINT"]
    points = theirs["data"]["points"]  # (4, P, F) in the file's units, NaN where missing
    count = points.shape[1]
    assert ours.points.shape == (points.shape[2], count, 3), "frames and points"
    labels = []
    for group in ["LABELS"] + [f"LABELS{i}" for i in range(2, 100)]:
        if group not in point:
            break
        labels += point[group]["value"]
    # ezc3d drops the trailing blanks of a label, s2kf keeps the label as stored without them too.
    assert ours.raw_labels == labels[:count], "labels"
    rate = float(point["RATE"]["value"][0]) if "RATE" in point else float(header["frame_rate"])
    assert ours.rate == pytest.approx(rate, rel=1e-6), "rate"
    # ezc3d counts frames from 0 (header word 4 minus 1); s2kf keeps the header's 1-based number.
    assert ours.first_frame == header["first_frame"] + 1, "first frame"
    units = point["UNITS"]["value"][0] if "UNITS" in point else "mm"
    assert ours.units.strip() == units.strip(), "units"

    xyz = np.transpose(points[:3], (2, 1, 0)) * ours.to_mm  # (F, P, 3) in mm
    their_missing = np.isnan(xyz).any(axis=2)
    our_missing = ~ours.visible
    assert not (their_missing & ~our_missing).any(), "a sample ezc3d marks missing is visible in s2kf"
    # s2kf also reads a marker exactly at (0, 0, 0) as missing (docs/c3d.md); ezc3d returns it.
    extra = our_missing & ~their_missing
    at_origin = (xyz == 0).all(axis=2) & ~np.asarray(ours.model_output)[None, :]
    assert not (extra & ~at_origin).any(), "s2kf marks missing a sample ezc3d reads, not at (0, 0, 0)"
    both = ~our_missing
    difference = np.abs(ours.points[both] - xyz[both])
    # float32 storage: the same numbers; integer storage: int x scale in float32 (ezc3d) or double.
    tolerance = 1e-6 * np.maximum(1.0, np.abs(xyz[both]))
    assert (difference <= tolerance).all(), f"coordinates differ by up to {difference.max():.3g} mm"
    return dict(
        frames=points.shape[2],
        points=count,
        missing=int(their_missing.sum()),
        origin_missing=int(extra.sum()),
        largest_mm=float(difference.max()) if difference.size else 0.0,
    )


@pytest.mark.parametrize("path", c3d_files(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_ezc3d_reads_what_s2kf_reads(path):
    known = DIFFERENCES.get(path.name)
    if known is None:
        compare(path)
        return
    if "rejects" in known:
        refusal = ezc3d_refusal(path)
        assert refusal != "read", "ezc3d now reads this file: compare it"
        # Out of the child's memory: the allocation ezc3d makes before its own refusal.
        assert known["rejects"] in refusal or refusal == "std::bad_alloc", f"ezc3d now fails otherwise: {refusal}"
    else:
        assert known["misreads"](ezc3d.c3d(str(path))), "ezc3d now reads this file: compare it"
    if "s2kf_rejects" in known:
        with pytest.raises(OSError, match=known["s2kf_rejects"]):
            s2kf.read_c3d(str(path))
    else:
        assert s2kf.read_c3d(str(path)).points.shape[:2] == known["shape"], "frames and points"


def test_every_file_is_covered():
    # The glob must find the bundled files: a moved data folder must not make this test pass empty.
    names = {p.name for p in c3d_files()}
    assert len(names) >= 20 and set(DIFFERENCES) <= names


def table():
    """The rows of docs/c3d.md's table: file, agree/differ, figures or why."""
    rows = ["| file | ezc3d and s2kf | frames × points, missing samples, largest difference; or why |", "|---|---|---|"]
    for path in c3d_files():
        name = path.relative_to(SOURCE_DIR)
        if path.name in DIFFERENCES:
            rows.append(f"| {name} | differ | {DIFFERENCES[path.name]['why']} |")
            continue
        r = compare(path)
        origin = f" (+{r['origin_missing']} at (0, 0, 0), missing for s2kf)" if r["origin_missing"] else ""
        rows.append(f"| {name} | agree | {r['frames']} × {r['points']}, {r['missing']} missing{origin}, "
                    f"{r['largest_mm']:.3g} mm |")
    return "\n".join(rows)


if __name__ == "__main__":
    print(table())
