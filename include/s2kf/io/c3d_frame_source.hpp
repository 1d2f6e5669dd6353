/// @file
/// A C3D file as a frame source: frames are read from the file as the pipeline asks for them, so
/// memory does not grow with the recording's length.
#pragma once

#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/frame_source.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace s2kf::c3d {

class C3dFrameSource : public FrameSource {
 public:
  /// Opens `path`; throws C3dError if it is not a readable C3D file.
  explicit C3dFrameSource(const std::string& path) : reader_(path), labels_(marker_labels(reader_.info())) {}

  const C3dInfo& info() const { return reader_.info(); }
  const std::vector<std::string>& labels() const override { return labels_; }
  double rate_hz() const override { return reader_.info().rate; }
  std::int64_t frame_count() const override { return reader_.info().frame_count; }
  bool read(std::int64_t index, MarkerFrame& frame) override {
    if (index < 0 || index >= frame_count()) return false;
    if (reader_.next_frame() != index) reader_.seek_frame(index);
    return reader_.read_frame(frame);
  }

 private:
  C3dReader reader_;
  std::vector<std::string> labels_;
};

}  // namespace s2kf::c3d
