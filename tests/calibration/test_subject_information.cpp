// The subject's information from the data at known poses (calibration/subject_information.hpp),
// checked by what it must be whatever the body: a symmetric positive semi-definite matrix over the
// length factors and the mapped markers' offsets, nothing for a marker no frame shows, and, with
// every pose counted twice, twice the offsets' information while the length factors' stays (their
// prior grows with the frames) and the threshold doubles.
#include <s2kf/body/body_model.hpp>
#include <s2kf/calibration/subject_information.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

#include <stdexcept>
#include <utility>
#include <vector>

namespace {

using namespace s2kf;

constexpr double kNoiseVariance = 100.0;  // (10 mm)^2

struct Sweep {
  sim::Subject subject;
  sim::Recording recording;
  body::MarkerMapping mapping;
  std::vector<std::pair<long, body::Pose>> poses;
};

Sweep sweep() {
  Sweep s{sim::make_subject(body::mmm_body_model(1750), sim::SubjectOptions{}, 3), {}, {}, {}};
  sim::RandomSweepOptions motion;
  motion.duration_s = 3;
  sim::RecordingOptions options;
  options.frames = 120;
  s.recording = sim::simulate_recording(sim::random_sweep_motion(3, s.subject.lower, s.subject.upper, motion),
                                        s.subject, options, 3);
  for (int m = 0; m < s.subject.model.marker_count(); ++m) s.mapping.point_of_marker.push_back(m);
  for (long k = 0; k < 120; k += 10) s.poses.emplace_back(k, s.recording.truth[static_cast<std::size_t>(k)]);
  return s;
}

calibration::SubjectInformation information_of(const Sweep& s, double prior_only_fraction = 0.01) {
  return calibration::subject_information(body::mmm_body_model(1750), s.subject.model, s.mapping, s.recording,
                                          s.poses, calibration::CalibrationOptions{}, kNoiseVariance,
                                          prior_only_fraction);
}

TEST(SubjectInformation, IsSymmetricPositiveSemiDefiniteOverTheLengthFactorsAndOffsets) {
  const Sweep s = sweep();
  const calibration::SubjectInformation info = information_of(s);
  const Eigen::Index unknowns =
      static_cast<Eigen::Index>(info.segments.size()) + 3 * s.subject.model.marker_count();
  ASSERT_FALSE(info.segments.empty());
  ASSERT_EQ(info.information.rows(), unknowns);
  ASSERT_EQ(info.information.cols(), unknowns);
  ASSERT_EQ(info.prior_sd.size(), unknowns);
  EXPECT_EQ(info.frames_used, static_cast<long>(s.poses.size()));
  EXPECT_LT((info.information - info.information.transpose()).norm(), 1e-9 * info.information.norm());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(info.information);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), -1e-8 * eigen.eigenvalues().maxCoeff());
  EXPECT_GT(eigen.eigenvalues().maxCoeff(), 1.0);  // the data outweigh the prior somewhere
  // The threshold: the fraction of a marker coordinate's information seen in every frame,
  // frames x (offset prior SD / noise)^2.
  const calibration::CalibrationOptions defaults;
  EXPECT_NEAR(info.threshold,
              0.01 * 12 * defaults.offset_prior_sd_mm * defaults.offset_prior_sd_mm / kNoiseVariance, 1e-12);
}

TEST(SubjectInformation, AMarkerNoFrameShowsGivesNoInformationAndAnUnmappedOneIsNoUnknown) {
  Sweep s = sweep();
  s.recording.visible.row(5).setConstant(false);
  const calibration::SubjectInformation hidden = information_of(s);
  const Eigen::Index at = static_cast<Eigen::Index>(hidden.segments.size()) + 3 * 5;
  EXPECT_EQ(hidden.information.middleRows(at, 3).norm(), 0.0);
  EXPECT_GT(hidden.information.middleRows(at + 3, 3).norm(), 0.0);  // the next marker's is there

  s.mapping.point_of_marker[5] = -1;
  const calibration::SubjectInformation unmapped = information_of(s);
  EXPECT_EQ(unmapped.information.rows(), hidden.information.rows() - 3);
}

TEST(SubjectInformation, EveryPoseTwiceDoublesTheOffsetsInformationAndKeepsTheLengthFactors) {
  Sweep s = sweep();
  const calibration::SubjectInformation once = information_of(s);
  const auto poses = s.poses;
  s.poses.insert(s.poses.end(), poses.begin(), poses.end());
  const calibration::SubjectInformation twice = information_of(s);
  const Eigen::Index scales = static_cast<Eigen::Index>(once.segments.size());
  const Eigen::Index offsets = once.information.rows() - scales;
  EXPECT_EQ(twice.frames_used, 2 * once.frames_used);
  EXPECT_NEAR(twice.threshold, 2 * once.threshold, 1e-12);
  const auto close = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return (a - b).norm() <= 1e-8 * (1.0 + b.norm());
  };
  EXPECT_TRUE(close(twice.information.bottomRightCorner(offsets, offsets),
                    2.0 * once.information.bottomRightCorner(offsets, offsets)));
  EXPECT_TRUE(
      close(twice.information.topLeftCorner(scales, scales), once.information.topLeftCorner(scales, scales)));
  EXPECT_TRUE(close(twice.information.topRightCorner(scales, offsets),
                    std::sqrt(2.0) * once.information.topRightCorner(scales, offsets)));
}

TEST(SubjectInformation, APoseOutsideTheRecordingIsRefused) {
  Sweep s = sweep();
  s.poses.emplace_back(120, s.recording.truth.back());
  EXPECT_THROW(information_of(s), std::invalid_argument);
}

}  // namespace
