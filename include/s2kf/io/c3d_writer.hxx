/// @file
/// The definitions of <s2kf/io/c3d_writer.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/io/c3d_writer.hpp>

namespace s2kf::c3d {

S2KF_INLINE void C3dStreamWriter::append(
    const Eigen::Ref<const Eigen::Matrix3Xd>& positions,
    const Eigen::Ref<const Eigen::Array<bool, Eigen::Dynamic, 1>>& visible) {
  if (positions.cols() != points_ || visible.size() != points_)
    fail("a frame of " + std::to_string(positions.cols()) + " points and " + std::to_string(visible.size()) +
         " visibility flags for a file of " + std::to_string(points_) + " points");
  append_columns(positions.data(), positions.outerStride(), visible.data());
}

S2KF_INLINE void C3dStreamWriter::finish() {
  if (finished_) return;
  if (!file_.is_open()) fail("the writer was already closed after an error");
  const std::int64_t data_end = static_cast<std::int64_t>(head_.size()) + frames_ * points_ * 16;
  const std::int64_t padding = (512 - data_end % 512) % 512;
  const std::vector<char> zeros(static_cast<std::size_t>(padding), 0);
  file_.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
  const std::uint16_t short_frames = static_cast<std::uint16_t>(std::min<std::int64_t>(frames_, 65535));
  // Float storage: |scale| only scales residuals, but c3d.org asks for max|coordinate|/32000.
  const float scale = -static_cast<float>(std::max(max_abs_, 1.0) / 32000.0);
  std::uint8_t word[4];
  detail::put_u16(word, short_frames);
  patch(8, word, 2);  // header last frame (first frame is 1)
  patch(parameters_at_ + frames_at_, word, 2);
  detail::put_f32(word, scale);
  patch(12, word, 4);
  patch(parameters_at_ + scale_at_, word, 4);
  detail::put_f32(word, static_cast<float>(frames_));
  patch(parameters_at_ + long_frames_at_, word, 4);
  detail::put_u16(word, static_cast<std::uint16_t>(frames_ & 0xFFFF));
  detail::put_u16(word + 2, static_cast<std::uint16_t>((frames_ >> 16) & 0xFFFF));
  patch(parameters_at_ + end_field_at_, word, 4);
  file_.flush();
  check_stream();
  file_.close();
  if (file_.fail()) fail("cannot close " + temporary_);
  std::error_code error;
  std::filesystem::rename(temporary_, path_, error);
  if (error) fail("cannot rename " + temporary_ + " to " + path_ + ": " + error.message());
  finished_ = true;
}

S2KF_INLINE void C3dStreamWriter::append_columns(const double* xyz, Eigen::Index stride,
                                                 const bool* visible) {
  std::uint8_t* out = frame_.data();
  for (int p = 0; p < points_; ++p, out += 16) {
    const double* c = xyz + stride * p;
    const bool present = (visible == nullptr || visible[p]) && std::isfinite(c[0]) && std::isfinite(c[1]) &&
                         std::isfinite(c[2]);
    const float w[4] = {present ? static_cast<float>(c[0]) : 0.0f, present ? static_cast<float>(c[1]) : 0.0f,
                        present ? static_cast<float>(c[2]) : 0.0f, present ? 0.0f : -1.0f};
    if (present) max_abs_ = std::max({max_abs_, std::abs(c[0]), std::abs(c[1]), std::abs(c[2])});
    std::memcpy(out, w, 16);
  }
  file_.write(reinterpret_cast<const char*>(frame_.data()), static_cast<std::streamsize>(frame_.size()));
  check_stream();
  ++frames_;
}

S2KF_INLINE void write_c3d(const std::string& path, const std::vector<std::string>& labels, double rate,
                           const Eigen::MatrixXd& positions,
                           const Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>& visible,
                           const std::vector<std::string>& descriptions) {
  const Eigen::Index points = static_cast<Eigen::Index>(labels.size());
  if (positions.rows() != 3 * points)
    throw C3dError(path, -1,
                   "positions have " + std::to_string(positions.rows()) + " rows, expected 3 x " +
                       std::to_string(points) + " labels");
  const bool masked = visible.size() > 0;
  if (masked && (visible.rows() != points || visible.cols() != positions.cols()))
    throw C3dError(path, -1, "the visibility mask does not match the positions");
  C3dStreamWriter writer(path, labels, rate, descriptions);
  for (Eigen::Index f = 0; f < positions.cols(); ++f) {
    const Eigen::Map<const Eigen::Matrix3Xd> frame(positions.col(f).data(), 3, points);
    if (masked)
      writer.append(frame, visible.col(f));
    else
      writer.append(frame);
  }
  writer.finish();
}

S2KF_INLINE void write_c3d(const std::string& path, const Recording& recording) {
  std::vector<std::string> labels;
  labels.reserve(recording.info.labels.size());
  for (const PointLabel& label : recording.info.labels) labels.push_back(stored_label(label));
  write_c3d(path, labels, recording.info.rate, recording.positions, recording.visible,
            recording.info.descriptions);
}

}  // namespace s2kf::c3d
