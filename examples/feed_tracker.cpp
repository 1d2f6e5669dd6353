// Feeding the tracker frame by frame, as a live system would (no calibration, no files): the
// model's markers mapped by name, then Tracker::process on every frame as it comes.
//   ./build/examples/example_feed_tracker data/handstand.c3d
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/io/c3d_error.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/track/tracker.hpp>

#include <cstdio>
#include <stdexcept>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s RECORDING.c3d (labelled with the model's own marker names)\n", argv[0]);
    return 2;
  }
  try {
    s2kf::c3d::C3dFrameSource source(argv[1]);
    const s2kf::body::BodyModel model = s2kf::body::mmm_body_model(1750);
    const s2kf::body::MarkerMapping mapping = s2kf::body::map_markers(source.labels(), model.marker_names());
    s2kf::track::TrackerOptions options;
    options.samples = 93;
    s2kf::track::Tracker tracker(
        model, mapping, options, source.rate_hz(),
        s2kf::lcd_sample_set(s2kf::track::Tracker::kRootDofs + model.joint_count(), options.samples).set);
    s2kf::MarkerFrame frame;
    double distance_sum = 0;
    long tracked = 0;
    for (std::int64_t f = 0; source.read(f, frame); ++f) {
      const s2kf::track::FrameEstimate& estimate = tracker.process(frame.positions, frame.visible);
      if (!estimate.tracked) continue;
      ++tracked;
      distance_sum += estimate.mean_marker_distance;
      if (f % 200 == 0)
        std::printf("frame %4lld: %2d markers seen, %5.1f mm from the model, %.2f ms\n",
                    static_cast<long long>(f), estimate.visible_markers, estimate.mean_marker_distance,
                    1e3 * estimate.seconds);
    }
    std::printf("%ld frames tracked, mean marker distance %.1f mm\n", tracked,
                tracked > 0 ? distance_sum / static_cast<double>(tracked) : 0.0);
    return tracked > 0 ? 0 : 1;
  } catch (const s2kf::c3d::C3dError& e) {
    std::fprintf(stderr, "%s: %s\n", argv[1], e.sentence().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", argv[1], e.what());
  }
  return 1;
}
