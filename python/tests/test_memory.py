"""Streaming 100,000 frames through the Tracker must not grow the process's memory: every frame
creates an estimate and its arrays, which must all be freed. Most frames have every marker hidden
(a prediction: microseconds), every 500th is a full frame (an S2KF update), so the test takes a
few seconds and still runs both paths through the bindings."""
import numpy as np

import s2kf


def resident_bytes():
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * 4096


def test_no_memory_growth_over_100000_streamed_frames():
    sim = s2kf.simulate("walk", frames=200, seed=4)
    tracker = s2kf.Tracker(sim.labels, sim.rate, samples=101)
    hidden = np.full((50, 3), np.nan)
    visible = np.ones(50, dtype=bool)

    def stream(first, count):
        for k in range(first, first + count):
            full = k % 500 == 0
            e = tracker.process(sim.points[(k // 500) % 200] if full else hidden, visible)
            # Touch every array the estimate hands out.
            e.pose, e.covariance, e.predicted_markers, e.marker_distance, e.root_rotation
            assert e.tracked

    stream(0, 10_000)  # warm-up: buffers, allocator arenas
    before = resident_bytes()
    stream(10_000, 90_000)
    growth = resident_bytes() - before
    # One leaked estimate per frame would be ~20 KB x 90,000; one leaked 3-vector ~9 MB.
    assert growth < 1 << 20, f"resident memory grew by {growth / 1e6:.1f} MB over 90,000 frames"
    assert tracker.frames_processed == 100_000
