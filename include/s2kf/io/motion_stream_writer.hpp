/// @file
/// Writing a motion's CSV, OpenSim .mot, BVH, MMM and velocity/acceleration files frame by frame, with memory
/// that does not grow with the recording: what `s2kf track` uses for recordings of any length.
#pragma once

#include <s2kf/body/body_model.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/bvh.hpp>
#include <s2kf/io/mmm_motion.hpp>
#include <s2kf/io/motion_derivatives.hpp>
#include <s2kf/io/motion_files.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace s2kf::io {

/// Where MotionStreamWriter writes; an empty path leaves that format out.
struct MotionFilePaths {
  std::string csv;               ///< write_motion_csv's format
  std::string mot;               ///< write_opensim_mot's format
  std::string bvh;               ///< write_bvh's format
  std::string mmm;               ///< write_mmm_motion's format
  std::string velocity_csv;      ///< motion_derivatives' velocities in write_motion_csv's format
  std::string acceleration_csv;  ///< and its accelerations
};

/// Writes the motion files save_motion_csv, save_opensim_mot, save_bvh, save_mmm_motion and (the
/// derivatives) save_motion_csv of motion_derivatives would write for the same rows, byte for byte,
/// while the rows arrive one per frame (append()); memory stays constant. Files the caller writes
/// itself (a model, the markers) can join the same commit through companion().
///
/// The CSV goes straight to `csv + ".tmp"`. The .mot header counts the tracked rows and the BVH
/// header all frames, so their lines go to `path + ".body.tmp"` first and finish() writes header and
/// lines to `path + ".tmp"` (the MMM file's two sensors likewise). Untracked rows (a non-finite value) are
/// left out of the .mot and repeat the last tracked pose in the BVH; untracked rows before the first tracked
/// one are only counted and take the first tracked pose when it arrives (the rest pose if none ever does).
///
/// Nothing appears under the target names until finish() has written all files; they are
/// then renamed one after another. A writer destroyed without finish() (an exception, a failed run)
/// removes every temporary file and creates or replaces no target.
class MotionStreamWriter {
 public:
  /// `model` gives the joints (columns) and the BVH skeleton, `rate_hz` the BVH frame time and
  /// `mot_name` the first line of the .mot file.
  MotionStreamWriter(MotionFilePaths paths, const body::BodyModel& model, double rate_hz,
                     std::string mot_name, BvhUnits bvh_units = BvhUnits::metres)
      : paths_(std::move(paths)),
        joint_names_(model.joint_names()),
        skeleton_(model, bvh_units),
        height_mm_(model.height_mm),
        rate_hz_(rate_hz),
        mot_name_(std::move(mot_name)),
        last_tracked_(Eigen::VectorXd::Zero(6 + model.joint_count())) {
    if (!paths_.csv.empty()) {
      csv_.emplace(paths_.csv);
      write_motion_csv_header(csv_->stream(), joint_names_);
      csv_->check();
    }
    if (!paths_.mot.empty()) mot_body_.emplace(paths_.mot + ".body.tmp");
    if (!paths_.bvh.empty()) bvh_body_.emplace(paths_.bvh + ".body.tmp");
    if (!paths_.mmm.empty()) {
      mmm_pose_body_.emplace(paths_.mmm + ".pose.tmp");
      mmm_joint_body_.emplace(paths_.mmm + ".joints.tmp");
    }
    if (!paths_.velocity_csv.empty() || !paths_.acceleration_csv.empty()) {
      for (auto [path, file] : {std::pair{&paths_.velocity_csv, &velocity_csv_},
                                std::pair{&paths_.acceleration_csv, &acceleration_csv_}})
        if (!path->empty()) {
          file->emplace(*path);
          write_motion_csv_header((*file)->stream(), joint_names_);
        }
      derivatives_.emplace([this](long frame, double time, const Eigen::VectorXd& velocity,
                                  const Eigen::VectorXd& acceleration) {
        if (velocity_csv_) write_motion_csv_row(velocity_csv_->stream(), frame, time, velocity);
        if (acceleration_csv_) write_motion_csv_row(acceleration_csv_->stream(), frame, time, acceleration);
      });
    }
  }

  /// A file the caller writes (e.g. the .osim model, the .trc markers) that is committed with the
  /// motion files by finish() and discarded with them otherwise. Throws std::runtime_error when it
  /// cannot be opened.
  std::ostream& companion(const std::string& path);
  MotionStreamWriter(const MotionStreamWriter&) = delete;
  MotionStreamWriter& operator=(const MotionStreamWriter&) = delete;
  ~MotionStreamWriter() = default;  // the members remove their temporary files unless finished

  /// Columns of a row: 6 (root position, roll/pitch/yaw) + joints.
  Eigen::Index columns() const { return last_tracked_.size(); }
  long frames() const { return frames_; }
  long tracked_frames() const { return tracked_; }
  bool finished() const { return finished_; }

  /// Adds the next frame: its number in the recording, its time (s) and its row of columns() values
  /// (NaN where the frame was not tracked). Throws std::runtime_error when a file cannot be written.
  void append(long frame, double time, const MotionRowRef& values);

  /// The CSV as written so far, flushed, under its temporary name (the target's until finish()):
  /// what a caller reads back before the set is committed (accuracy against a truth). Throws
  /// std::logic_error when no CSV is written, std::runtime_error when it cannot be written.
  std::string flushed_csv();

  /// Same, with the row given as "not tracked".
  void append_untracked(long frame, double time);

  /// Writes the headers, then renames the files (the companions last) to their target names. On failure every
  /// temporary file is removed and std::runtime_error is thrown (targets renamed before the failing
  /// one stay).
  void finish();

 private:
  /// A scratch file beside a target, removed when destroyed.
  class ScratchFile {
   public:
    explicit ScratchFile(std::string path) : path_(std::move(path)) {
      stream_.open(path_, std::ios::in | std::ios::out | std::ios::trunc);
      if (!stream_) throw std::runtime_error("cannot open " + path_ + " for writing");
    }
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;
    ~ScratchFile() {
      stream_.close();
      std::error_code ignored;
      std::filesystem::remove(path_, ignored);
    }
    std::ostream& stream() { return stream_; }
    void check() const {
      if (!stream_) throw std::runtime_error("cannot write " + path_ + " (disk full or no permission?)");
    }
    /// Appends everything written so far to `out`.
    void copy_to(std::ostream& out) {
      stream_.flush();
      check();
      stream_.seekg(0);
      if (stream_.peek() != std::fstream::traits_type::eof()) out << stream_.rdbuf();
      stream_.clear();
      check();
    }

   private:
    std::string path_;
    std::fstream stream_;
  };

  MotionFilePaths paths_;
  std::vector<std::string> joint_names_;
  BvhSkeleton skeleton_;
  double height_mm_;  ///< the MMM file's subject height
  double rate_hz_;
  std::string mot_name_;
  std::optional<AtomicFileWriter> csv_;
  std::optional<ScratchFile> mot_body_, bvh_body_, mmm_pose_body_, mmm_joint_body_;
  std::optional<AtomicFileWriter> velocity_csv_, acceleration_csv_;
  std::optional<MotionDerivativeStream> derivatives_;
  std::vector<std::unique_ptr<AtomicFileWriter>> companions_;
  Eigen::VectorXd last_tracked_;  ///< the BVH pose of untracked rows; zero (rest) until one is tracked
  long frames_ = 0;
  long tracked_ = 0;
  long untracked_before_first_ = 0;
  bool finished_ = false;
};

// The definitions: inline here by default, or compiled once (core/compilation_mode.hpp).
#if S2KF_DEFINE_HEAVY

S2KF_INLINE std::ostream& MotionStreamWriter::companion(const std::string& path) {
  if (finished_) throw std::logic_error("MotionStreamWriter::companion after finish()");
  companions_.push_back(std::make_unique<AtomicFileWriter>(path));
  return companions_.back()->stream();
}

S2KF_INLINE void MotionStreamWriter::append(long frame, double time, const MotionRowRef& values) {
  if (finished_) throw std::logic_error("MotionStreamWriter::append after finish()");
  if (values.size() != columns())
    throw std::invalid_argument("MotionStreamWriter::append: a row of " + std::to_string(values.size()) +
                                " values, expected " + std::to_string(columns()));
  if (csv_) {
    write_motion_csv_row(csv_->stream(), frame, time, values);
    csv_->check();
  }
  ++frames_;
  if (derivatives_) derivatives_->push(frame, time, values);
  if (!is_tracked_row(values)) {
    if (tracked_ == 0)
      ++untracked_before_first_;
    else if (bvh_body_)
      skeleton_.write_row(bvh_body_->stream(), last_tracked_);
  } else {
    if (mot_body_) write_opensim_mot_row(mot_body_->stream(), time, values);
    if (mmm_pose_body_) {
      write_mmm_model_pose(mmm_pose_body_->stream(), time, values);
      write_mmm_joint_position(mmm_joint_body_->stream(), time, values);
    }
    if (bvh_body_)
      for (long r = tracked_ == 0 ? untracked_before_first_ : 0; r >= 0; --r)
        skeleton_.write_row(bvh_body_->stream(), values);
    last_tracked_ = values;
    ++tracked_;
  }
  if (mot_body_) mot_body_->check();
  if (bvh_body_) bvh_body_->check();
  if (mmm_pose_body_) mmm_pose_body_->check(), mmm_joint_body_->check();
  if (velocity_csv_) velocity_csv_->check();
  if (acceleration_csv_) acceleration_csv_->check();
}

S2KF_INLINE std::string MotionStreamWriter::flushed_csv() {
  if (!csv_ || finished_) throw std::logic_error("MotionStreamWriter::flushed_csv without a CSV in progress");
  csv_->stream().flush();
  csv_->check();
  return csv_->temporary_path().string();
}

S2KF_INLINE void MotionStreamWriter::append_untracked(long frame, double time) {
  append(frame, time, Eigen::VectorXd::Constant(columns(), std::numeric_limits<double>::quiet_NaN()));
}

S2KF_INLINE void MotionStreamWriter::finish() {
  if (finished_) return;
  std::optional<AtomicFileWriter> mot, bvh, mmm;
  if (mot_body_) {
    mot.emplace(paths_.mot);
    write_opensim_mot_header(mot->stream(), mot_name_, joint_names_, static_cast<std::size_t>(tracked_));
    mot_body_->copy_to(mot->stream());
    mot->check();
  }
  if (bvh_body_) {
    bvh.emplace(paths_.bvh);
    skeleton_.write_hierarchy(bvh->stream());
    BvhSkeleton::write_motion_header(bvh->stream(), frames_, rate_hz_);
    bvh_body_->copy_to(bvh->stream());
    if (tracked_ == 0)  // never tracked: the rest pose throughout
      for (long r = 0; r < untracked_before_first_; ++r) skeleton_.write_row(bvh->stream(), last_tracked_);
    bvh->check();
  }
  if (mmm_pose_body_) {
    mmm.emplace(paths_.mmm);
    write_mmm_header(mmm->stream(), mot_name_, height_mm_);
    mmm_pose_body_->copy_to(mmm->stream());
    write_mmm_kinematic_header(mmm->stream(), joint_names_);
    mmm_joint_body_->copy_to(mmm->stream());
    write_mmm_footer(mmm->stream());
    mmm->check();
  }
  if (derivatives_) derivatives_->finish();
  for (std::optional<AtomicFileWriter>* file : {&velocity_csv_, &acceleration_csv_})
    if (*file) (*file)->check();
  for (const auto& companion : companions_) companion->check();
  mot_body_.reset();
  bvh_body_.reset();
  mmm_pose_body_.reset();
  mmm_joint_body_.reset();
  if (csv_) csv_->commit();
  if (mot) mot->commit();
  if (bvh) bvh->commit();
  if (mmm) mmm->commit();
  if (velocity_csv_) velocity_csv_->commit();
  if (acceleration_csv_) acceleration_csv_->commit();
  for (const auto& companion : companions_) companion->commit();
  finished_ = true;
}

#endif  // S2KF_DEFINE_HEAVY

}  // namespace s2kf::io
