/// @file
/// The definitions of <s2kf/io/motion_stream_writer.hpp>: inline where the library is used header-only,
/// compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/motion_stream_writer.hpp>

namespace s2kf::io {

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

}  // namespace s2kf::io
