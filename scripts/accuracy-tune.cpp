// The tuning driver behind the motion-model and calibration-prior choices in docs/tracking.md and
// docs/notes/: one simulated realistic subject and motion, tracked as `s2kf track` tracks it (marker set
// chosen from the labels, calibration unless 0), with the tracker's motion model and noise levels given on
// the command line; prints the accuracy against the truth after 20 frames (and the true-subject reference
// when asked). Not built by CMake; build it from the repository root with
//   g++ -O2 -DNDEBUG -std=c++17 -Iinclude -isystem /usr/include/eigen3 \
//     -DS2KF_DATA_DIR="\"$PWD/data\"" scripts/accuracy-tune.cpp src/app/sample_sets.cpp
//     src/app/marker_set_json.cpp \ src/app/data_directory.cpp -o accuracy-tune
// or, faster, against the compiled library (`cmake --build build --target s2kf_compiled`; the same
// -march=native as that library, or Eigen's objects differ in layout and the program crashes):
//   g++ -O2 -march=native -DNDEBUG -std=c++17 -DS2KF_COMPILED -Iinclude \
//     -isystem /usr/include/eigen3 -DS2KF_DATA_DIR="\"$PWD/data\"" scripts/accuracy-tune.cpp \
//     src/app/sample_sets.cpp src/app/marker_set_json.cpp src/app/data_directory.cpp build/libs2kf_compiled.a
//     -lpthread -o build/accuracy-tune
// Usage: accuracy-tune MOTION SEED OCCLUSION(0|1) SMOOTH(0|1) CALIBRATE(0|1) rw|cv
//          [POSITION_ACC ORIENTATION_ACC JOINT_ACC POSITION_SPEED ORIENTATION_SPEED JOINT_SPEED
//           REFERENCE(0|1) [INITIAL_RATE_SDS x3]]
// Environment: OFFSET_SD, SCALE_SD (calibration priors), NOSCALE (offsets only), PRIOR_ONLY (the
// calibration's prior_only_fraction), PRIOR_SHARE (prior_only_share: the fraction thresholds the
// surviving share), SHRINK (weak_direction_shrink), SEGMENTS
// (per segment), DIRECTIONS (the directions left to the prior), SUBJECT (the calibrated and the
// nominal subject's offset and bone-length errors against the true subject), SOFT_TISSUE (the
// subject's soft-tissue scale, mm), FLEXION_SPEED (the limbs' flexion joints' random-walk speed;
// JOINT_SPEED above is every other joint's).
#include <cstdio>
#include <cstdlib>
#include <map>
#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/motion_json.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/evaluation/true_subject_reference.hpp>
#include <s2kf/evaluation/truth_metrics.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/sim/recording.hpp>
#include <string>
using namespace s2kf;
int main(int argc, char** argv) {
  // usage: tune motion seed occlusion(0/1) smooth(0/1) calibrate(0/1) model(rw/cv) pa oa ja ps os js ref(0/1)
  std::string motion_name = argv[1];
  const unsigned seed = std::atoi(argv[2]);
  const bool occl = std::atoi(argv[3]), smooth = std::atoi(argv[4]), calib = std::atoi(argv[5]);
  sim::SubjectOptions so;
  if (const char* v = std::getenv("SOFT_TISSUE")) so.soft_tissue_mm = std::atof(v);
  const sim::Subject subject = sim::make_subject(body::mmm_body_model(so.height_mm), so, seed);
  app::JointTable joints{subject.joint_names, subject.lower, subject.upper};
  const auto motion =
      app::load_motion_file(std::string(S2KF_DATA_DIR) + "/motions/" + motion_name + ".json", joints, seed);
  sim::RecordingOptions ro;
  if (occl) ro.occlusion = {sim::kPaperOcclusionProbability, sim::kPaperOcclusionMeanFrames};
  const sim::Recording rec = sim::simulate_recording(motion, subject, ro, seed);
  pipeline::SessionOptions opt;
  opt.calibrate = calib;
  if (const char* v = std::getenv("OFFSET_SD")) opt.calibration.offset_prior_sd_mm = std::atof(v);
  if (const char* v = std::getenv("SCALE_SD")) opt.calibration.scale_prior_sd_per_frame = std::atof(v);
  if (const char* v = std::getenv("NOSCALE")) opt.calibration.estimate_segment_scales = false;
  if (const char* v = std::getenv("PRIOR_ONLY")) opt.calibration.prior_only_fraction = std::atof(v);
  if (std::getenv("PRIOR_SHARE")) opt.calibration.prior_only_share = true;
  if (const char* v = std::getenv("SHRINK")) opt.calibration.weak_direction_shrink = std::atof(v);
  if (const char* v = std::getenv("FLEXION_SPEED")) opt.tracker.flexion_speed_per_s = std::atof(v);
  std::string model = argv[6];
  opt.tracker.motion_model =
      model == "cv" ? track::MotionModel::constant_velocity : track::MotionModel::random_walk;
  if (argc > 7) {
    opt.tracker.position_acceleration = std::atof(argv[7]);
    opt.tracker.orientation_acceleration = std::atof(argv[8]);
    opt.tracker.joint_acceleration = std::atof(argv[9]);
    opt.tracker.position_speed_mm_per_s = std::atof(argv[10]);
    opt.tracker.orientation_speed_rad_per_s = std::atof(argv[11]);
    opt.tracker.joint_speed_per_s = std::atof(argv[12]);
  }
  const bool ref = argc > 13 && std::atoi(argv[13]);
  if (argc > 16) {
    opt.tracker.initial_position_rate_sd = std::atof(argv[14]);
    opt.tracker.initial_orientation_rate_sd = std::atof(argv[15]);
    opt.tracker.initial_joint_rate_sd = std::atof(argv[16]);
  }
  SequenceFrameSource source(rec);
  const body::MarkerSet set = app::choose_marker_set_for(rec.labels, "", "").set;
  const SampleSet samples = app::cached_sample_set(46, opt.tracker.samples);
  const pipeline::Session session = pipeline::prepare_session(source, set, opt, samples);
  pipeline::RunOptions run_options;
  run_options.smooth = smooth;
  SequenceFrameSource source2(rec);
  const track::TrackingRun run = pipeline::run_session(session, source2, samples, run_options);
  const io::MotionTable truth = sim::truth_motion(rec, session.model.joint_names());
  const auto t = evaluation::compare_with_truth(session.model, run.motion, truth, 20);
  std::vector<double> s = run.seconds;
  std::sort(s.begin(), s.end());
  std::printf("%s seed %u occl %d smooth %d: seg %.2f flex %.2f root %.2f viol %ld dist %.2f med %.2f ms",
              motion_name.c_str(), seed, occl, smooth, t.segment_orientation_rms_deg, t.limb_flexion_rms_deg,
              t.root_orientation_rms_deg, t.joint_limit_violations,
              track::mean_from(run.mean_marker_distance, 20), 1000 * s[s.size() / 2]);
  if (ref) {
    const auto r =
        evaluation::compare_with_truth(session.model, evaluation::true_subject_fit(subject, rec), truth, 20);
    std::printf(" | ref seg %.2f flex %.2f root %.2f", r.segment_orientation_rms_deg, r.limb_flexion_rms_deg,
                r.root_orientation_rms_deg);
  }
  std::printf("\n");
  if (std::getenv("DIRECTIONS") && session.calibration)
    for (const auto& pass : session.calibration->passes) {
      std::printf(" %d unknowns, %zu left to the prior:", pass.subject_unknowns, pass.prior_only.size());
      for (const auto& d : pass.prior_only)
        std::printf(" %s %.2g (%.0f%%)", d.segment.c_str(), d.information_ratio, 100 * d.share);
      std::printf("\n");
    }
  if (std::getenv("SUBJECT") && calib) {  // the calibrated and the nominal subject against the true one
    pipeline::SessionOptions nominal_options = opt;
    nominal_options.calibrate = false;
    SequenceFrameSource source3(rec);
    const body::BodyModel nominal = pipeline::prepare_session(source3, set, nominal_options, samples).model;
    const body::BodyModel& truth_model = subject.model;
    std::map<std::string, std::pair<double, int>> nominal_error, calibrated_error;
    for (const body::Marker& marker : truth_model.markers)
      for (int k = 0; k < session.model.marker_count(); ++k) {
        if (session.model.markers[k].name != marker.name || session.model.markers[k].frame != marker.frame)
          continue;
        const std::string segment = body::segment_of_frame(truth_model, marker.frame);
        const double en = (nominal.markers[k].offset - marker.offset).norm();
        const double ec = (session.model.markers[k].offset - marker.offset).norm();
        std::printf(" marker %s (%s): offset error %.1f mm nominal, %.1f calibrated\n", marker.name.c_str(),
                    segment.c_str(), en, ec);
        nominal_error[segment].first += en * en, ++nominal_error[segment].second;
        calibrated_error[segment].first += ec * ec, ++calibrated_error[segment].second;
      }
    for (const auto& [segment, e] : nominal_error)
      std::printf(" segment %s: RMS offset error %.1f mm nominal, %.1f calibrated\n", segment.c_str(),
                  std::sqrt(e.first / e.second),
                  std::sqrt(calibrated_error[segment].first / calibrated_error[segment].second));
    for (int j = 0; j < truth_model.joint_count(); ++j) {
      const double length = truth_model.joints[j].translation.norm();
      if (length > 0)
        std::printf(" bone %s: length error %+.1f %% nominal, %+.1f %% calibrated\n",
                    truth_model.joints[j].name.c_str(),
                    100 * (nominal.joints[j].translation.norm() / length - 1),
                    100 * (session.model.joints[j].translation.norm() / length - 1));
    }
  }
  if (std::getenv("SEGMENTS")) {
    for (const auto& [name, rms] : t.segment_rms_deg) std::printf(" %s %.1f", name.c_str(), rms);
    std::printf("\n");
  }
}
