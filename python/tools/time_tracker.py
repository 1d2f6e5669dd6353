"""Per-frame cost of the streaming Tracker from Python against the C++ it runs.

The same frames and warm-up as the C++ benchmark BM_TrackStep (benchmarks/bench_track.cpp): the
handstand recording, a tracker that has run its first 30 frames, then steady-state frames in a loop.
Reported per frame, best of 5 repetitions (the machine is shared):
  python   wall time of `tracker.process(points[f], visible[f])` in a Python loop, plus reading the
           pose (e.pose) as a user would;
  c++      the time the C++ Tracker::process reports for the same frames (FrameEstimate.seconds);
  overhead python / c++ - 1.
Compare `c++` with `build/benchmarks/bench_track --benchmark_filter='BM_TrackStep/L:301/visible:50'`.

  PYTHONPATH=build/python /usr/bin/python3 python/tools/time_tracker.py [--samples 301] [--frames 2000]
"""
import argparse
import os
import pathlib
import time

import numpy as np

import s2kf

WARMUP_FRAMES = 30


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=301)
    parser.add_argument("--frames", type=int, default=2000, help="steady-state frames per repetition")
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--height", type=float, default=1705.0, help="mm (the handstand's estimate)")
    arguments = parser.parse_args()
    data = pathlib.Path(os.environ.get("S2KF_DATA_DIR", pathlib.Path(__file__).resolve().parents[2] / "data"))
    rec = s2kf.read_c3d(str(data / "handstand.c3d"))
    points, visible = rec.points, rec.visible
    order = [WARMUP_FRAMES + k % (len(points) - WARMUP_FRAMES) for k in range(arguments.frames)]
    best_python, best_cpp = np.inf, np.inf
    for _ in range(arguments.repetitions):
        tracker = s2kf.Tracker(rec.labels, rec.rate, model=s2kf.BodyModel(arguments.height),
                               samples=arguments.samples)
        for f in range(WARMUP_FRAMES):
            tracker.process(points[f], visible[f])
        cpp = 0.0
        start = time.perf_counter()
        for f in order:
            e = tracker.process(points[f], visible[f])
            e.pose
            cpp += e.seconds
        python = (time.perf_counter() - start) / len(order)
        best_python, best_cpp = min(best_python, python), min(best_cpp, cpp / len(order))
    print(f"L = {arguments.samples}, {len(order)} frames x {arguments.repetitions}: "
          f"python {best_python * 1e3:.3f} ms, c++ {best_cpp * 1e3:.3f} ms per frame, "
          f"overhead {100 * (best_python / best_cpp - 1):.1f} % ({(best_python - best_cpp) * 1e6:.1f} us)")


if __name__ == "__main__":
    main()
