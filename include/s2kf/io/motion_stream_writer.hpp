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

}  // namespace s2kf::io

#if !defined(S2KF_COMPILED)
#include <s2kf/io/motion_stream_writer.hxx>
#endif
