// Which of a static trial's markers are the recording's: a marker the set does not name is kept only
// where its distances to the markers on its segment are the recording's; the set's named markers
// are the same landmarks in both trials and never judged.
#include <s2kf/body/body_model.hpp>
#include <s2kf/body/forward_kinematics.hpp>
#include <s2kf/body/marker_set.hpp>
#include <s2kf/body/pose.hpp>
#include <s2kf/calibration/static_trial_markers.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace {

using namespace s2kf;

/// `frames` copies of the model's markers at the zero pose, every point mapped to its marker.
MarkerSequence still_frames(const body::BodyModel& model, Eigen::Index frames) {
  const Eigen::Matrix3Xd points = body::marker_positions(model, body::zero_pose(model));
  MarkerSequence sequence;
  for (const body::Marker& marker : model.markers) sequence.labels.push_back(marker.name);
  sequence.rate_hz = 100;
  sequence.positions.resize(3 * points.cols(), frames);
  for (Eigen::Index f = 0; f < frames; ++f)
    sequence.positions.col(f) = Eigen::Map<const Eigen::VectorXd>(points.data(), points.size());
  sequence.visible.setConstant(points.cols(), frames, true);
  return sequence;
}

body::MarkerMapping identity(const body::BodyModel& model) {
  body::MarkerMapping mapping;
  for (int m = 0; m < model.marker_count(); ++m) mapping.point_of_marker.push_back(m);
  return mapping;
}

TEST(StaticTrialMarkers, AnUnnamedMarkerThatIsAnotherOneIsLeftOutAndNamedOnesAreNot) {
  const body::BodyModel model =
      body::apply_marker_set(body::mmm_body_model(1750), body::model_marker_set(body::mmm_body_model(1000)));
  // The frame with the most markers: the last three of them unnamed (placed by their motion).
  std::map<int, std::vector<int>> on_frame;
  for (int m = 0; m < model.marker_count(); ++m)
    on_frame[model.markers[static_cast<std::size_t>(m)].frame].push_back(m);
  const auto most = std::max_element(on_frame.begin(), on_frame.end(), [](const auto& a, const auto& b) {
    return a.second.size() < b.second.size();
  });
  const std::vector<int>& markers = most->second;
  ASSERT_GE(markers.size(), 6u);  // three named, three not
  std::vector<bool> named(static_cast<std::size_t>(model.marker_count()), true);
  const int wrong = markers[markers.size() - 1], right = markers[markers.size() - 2],
            also_right = markers[markers.size() - 3], moved_named = markers[0];
  for (const int m : {wrong, right, also_right}) named[static_cast<std::size_t>(m)] = false;

  const MarkerSequence recording = still_frames(model, 20);
  MarkerSequence trial = still_frames(model, 10);
  // Under `wrong`'s label the static trial shows another marker, 30 cm away; a named marker moved
  // as far is the set's landmark all the same.
  for (Eigen::Index f = 0; f < trial.frame_count(); ++f) {
    trial.positions.col(f).segment<3>(3 * wrong) += Eigen::Vector3d(300, 0, 0);
    trial.positions.col(f).segment<3>(3 * moved_named) += Eigen::Vector3d(0, 300, 0);
  }
  const std::vector<calibration::MovedMarker> moved = calibration::markers_moved_between_trials(
      model, identity(model), trial, identity(model), recording, named);
  ASSERT_EQ(moved.size(), 1u);
  EXPECT_EQ(moved[0].marker, wrong);
  EXPECT_GT(moved[0].mismatch_mm, 100);

  // Unmoved, every label is confirmed; with the others' distances only one agreeing marker left, an
  // unnamed marker is not (a single distance matches by chance too often).
  EXPECT_TRUE(calibration::markers_moved_between_trials(model, identity(model), still_frames(model, 10),
                                                        identity(model), recording, named)
                  .empty());
  MarkerSequence hidden = still_frames(model, 10);
  for (const int m : markers)
    if (m != right && m != markers[0]) hidden.visible.row(m).setConstant(false);
  const std::vector<calibration::MovedMarker> alone = calibration::markers_moved_between_trials(
      model, identity(model), hidden, identity(model), recording, named);
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_EQ(alone[0].marker, right);
}

}  // namespace
