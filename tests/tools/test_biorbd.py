"""The .bioMod that scripts/peer-benchmark.py gives biorbd (tests/tools/opensim_peer.py writes it from
s2kf's .osim) is s2kf's model: biorbd's marker positions at the .mot's coordinates equal the
program's model markers to 0.1 mm."""
import numpy as np
import pytest

import opensim_peer
from conftest import RECORDINGS

biorbd = opensim_peer.import_peer("biorbd")
osim = opensim_peer.import_peer("opensim")
if biorbd is None or osim is None:
    pytest.skip("PyPI has no biorbd or opensim wheel for this machine (CPython 3.11 on x86_64 Linux has "
                "both)", allow_module_level=True)


@pytest.mark.parametrize("name", RECORDINGS)
def test_biorbd_puts_every_marker_where_s2kf_does(tracked, name, scratch):
    run = tracked[name]
    prefix = str(run["prefix"])
    dofs = opensim_peer.osim_to_biomod(prefix + ".osim", scratch / (name + ".bioMod"))
    model = biorbd.Model(str(scratch / (name + ".bioMod")))
    assert model.nbQ() == len(dofs) == 46
    labels, mot_times, mot_values = opensim_peer.read_mot(osim, prefix + ".mot")
    header, csv_rows = opensim_peer.read_table(prefix + ".csv")
    marker_names = [n.to_string() for n in model.markerNames()]
    worst = 0.0
    for r in range(0, len(csv_rows), max(1, len(csv_rows) // 4)):
        if not np.all(np.isfinite(csv_rows[r])):
            continue
        m = int(np.argmin(np.abs(mot_times - csv_rows[r][header.index("time")])))
        q = np.array([mot_values[m][labels.index(d)] for d in dofs])
        at_biorbd = np.array([marker.to_array() for marker in model.markers(q)]) * 1000.0
        at_s2kf = opensim_peer.s2kf_model_markers(run["subject"], prefix + ".csv", r)
        for k, marker in enumerate(marker_names):
            error = float(np.linalg.norm(at_biorbd[k] - at_s2kf[marker]))
            assert error < 0.1, f"{name} row {r}: {marker} {error:.4f} mm apart"
            worst = max(worst, error)
    print(f"\n{name}: biorbd vs s2kf markers worst {worst:.2e} mm")
