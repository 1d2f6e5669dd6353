// The subject's information from the data at known poses (calibration/subject_information.hpp),
// checked by what it must be whatever the body: a symmetric positive semi-definite matrix over the
// length factors and the mapped markers' offsets, nothing for a marker no frame shows, and, with
// every pose counted twice, twice the offsets' information while the length factors' stays (their
// prior grows with the frames) and the threshold doubles; and, at one pose, the Schur complement of
// the normal equations of a Jacobian taken by central differences of the forward kinematics.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/calibration/subject_information.hpp>
#include <s2kf/sim/random_sweep.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <functional>
#include <stdexcept>
#include <string>
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

// The markers (3 x M, stacked) at a pose and a subject: the root moved by dx, turned by Exp(omega)
// on the right, the joints by dq; the segments' bones lengthened by (1 + their factor), the offsets
// moved by the subject step.
Eigen::VectorXd stacked_markers(const body::BodyModel& model, const body::Pose& pose,
                                const std::vector<std::string>& segments, const Eigen::VectorXd& pose_step,
                                const Eigen::VectorXd& subject_step) {
  body::BodyModel moved = model;
  for (body::Joint& joint : moved.joints) {
    const std::string segment = body::segment_of_frame(model, joint.parent_frame);
    for (std::size_t s = 0; s < segments.size(); ++s)
      if (segments[s] == segment) joint.translation *= 1.0 + subject_step(static_cast<Eigen::Index>(s));
  }
  const auto scales = static_cast<Eigen::Index>(segments.size());
  for (int m = 0; m < moved.marker_count(); ++m)
    moved.markers[static_cast<std::size_t>(m)].offset += subject_step.segment<3>(scales + 3 * m);
  const Eigen::Vector3d omega = pose_step.segment<3>(3);
  const Eigen::Matrix3d turn = omega.norm() > 0
                                   ? Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix()
                                   : Eigen::Matrix3d::Identity();
  const Eigen::Matrix3Xd markers =
      body::marker_positions(moved, pose.root_position + pose_step.head<3>(), pose.root_rotation() * turn,
                             pose.joints + pose_step.tail(pose.joints.size()));
  return Eigen::Map<const Eigen::VectorXd>(markers.data(), markers.size());
}

TEST(SubjectInformation, AtOnePoseIsTheSchurComplementOfTheFiniteDifferenceNormalEquations) {
  Sweep s = sweep();
  // A pose with every joint inside its limits (a joint on a limit is held there by the adjustment).
  const body::BodyModel& model = s.subject.model;
  std::size_t chosen = s.poses.size();
  for (std::size_t k = 0; k < s.poses.size() && chosen == s.poses.size(); ++k) {
    bool inside = true;
    for (int j = 0; j < model.joint_count(); ++j) {
      const double q = s.poses[k].second.joints(j);
      inside = inside && q > model.joints[static_cast<std::size_t>(j)].lower + 1e-3 &&
               q < model.joints[static_cast<std::size_t>(j)].upper - 1e-3;
    }
    if (inside) chosen = k;
  }
  ASSERT_LT(chosen, s.poses.size());
  s.poses = {s.poses[chosen]};
  const calibration::SubjectInformation info = information_of(s);
  const body::Pose& pose = s.poses.front().second;
  const auto n = static_cast<Eigen::Index>(6 + model.joint_count());
  const Eigen::Index unknowns = info.information.rows();
  // Central differences of the stacked markers over [pose, subject].
  Eigen::MatrixXd jacobian(3 * model.marker_count(), n + unknowns);
  const double h = 1e-5;
  for (Eigen::Index c = 0; c < n + unknowns; ++c) {
    Eigen::VectorXd step = Eigen::VectorXd::Zero(n + unknowns);
    step(c) = h;
    jacobian.col(c) = (stacked_markers(model, pose, info.segments, step.head(n), step.tail(unknowns)) -
                       stacked_markers(model, pose, info.segments, -step.head(n), -step.tail(unknowns))) /
                      (2 * h);
  }
  const Eigen::MatrixXd normal = jacobian.transpose() * jacobian / kNoiseVariance;
  Eigen::MatrixXd A = normal.topLeftCorner(n, n);
  A.diagonal().array() += 1e-9 * A.diagonal().maxCoeff();  // the adjustment's floor for unseen directions
  const Eigen::MatrixXd B = normal.topRightCorner(n, unknowns);
  const Eigen::MatrixXd reduced =
      normal.bottomRightCorner(unknowns, unknowns) - B.transpose() * A.llt().solve(B);
  const Eigen::MatrixXd expected = info.prior_sd.asDiagonal() * reduced * info.prior_sd.asDiagonal();
  EXPECT_LT((info.information - expected).norm(), 1e-6 * expected.norm());
  EXPECT_GT(expected.norm(), 1.0);
}

TEST(SubjectInformation, APoseOutsideTheRecordingIsRefused) {
  Sweep s = sweep();
  s.poses.emplace_back(120, s.recording.truth.back());
  EXPECT_THROW(information_of(s), std::invalid_argument);
}

}  // namespace
