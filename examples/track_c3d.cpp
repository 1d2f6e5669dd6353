// Tracking a C3D file with the library: prepare a session (marker mapping, height, subject
// calibration), run it, and print each 100th frame's root height and right knee angle.
//   ./build/examples/example_track_c3d data/walk.c3d
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/io/c3d_error.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/pipeline/session.hpp>

#include <cstdio>
#include <stdexcept>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s RECORDING.c3d (labelled with the model's own marker names)\n", argv[0]);
    return 2;
  }
  try {
    s2kf::c3d::C3dFrameSource source(argv[1]);
    // The model's own 50 markers; a lab's marker set would come from a marker-set file instead.
    const s2kf::body::MarkerSet set = s2kf::body::model_marker_set(s2kf::body::mmm_body_model(1000));
    s2kf::pipeline::SessionOptions options;
    options.tracker.samples = 93;  // fewer samples than the default 301: faster, a little less exact
    const s2kf::SampleSet samples = s2kf::lcd_sample_set(46, options.tracker.samples).set;
    const s2kf::pipeline::Session session = s2kf::pipeline::prepare_session(source, set, options, samples);
    const int knee = session.model.joint_index("RKx");
    s2kf::pipeline::RunHooks hooks;
    hooks.sink = [&](const s2kf::track::TrackedFrame& row) {  // row.values: root pose + 40 joints
      if (row.frame % 100 == 0)
        std::printf("frame %4ld: root height %7.1f mm, right knee %6.1f deg, marker distance %5.1f mm\n",
                    row.frame, row.values(2), row.values(6 + knee) * s2kf::kDegreesPerRadian,
                    row.mean_marker_distance);
    };
    const s2kf::track::TrackingRun run = s2kf::pipeline::run_session(session, source, samples, {}, hooks);
    std::printf("tracked %ld of %lld frames with %d markers, body height %.0f mm\n", run.frames_tracked,
                static_cast<long long>(source.frame_count()), session.markers_used(), session.height_mm);
    return run.frames_tracked > 0 ? 0 : 1;
  } catch (const s2kf::c3d::C3dError& e) {
    std::fprintf(stderr, "%s: %s\n", argv[1], e.sentence().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", argv[1], e.what());
  }
  return 1;
}
