/// @file
/// `s2kf live --osc`: each tracked frame as one Open Sound Control message (docs/live.md), encoded
/// by liblo and sent by the live UDP sender, which never waits.
#pragma once

#include <s2kf/track/tracking_run.hpp>

#include <lo/lo.h>

#include <cstdint>
#include <new>
#include <vector>

namespace s2kf::cli {

/// The OSC address of a pose message.
inline constexpr const char* kOscPoseAddress = "/s2kf/pose";

/// The bytes of one OSC message /s2kf/pose with the arguments int32 frame, float32 time (s),
/// int32 visible markers, then float32 per pose column (root position mm, root orientation and
/// joint angles rad, in PREFIX.csv's order; NaN where not tracked).
inline std::vector<char> osc_pose_message(const track::TrackedFrame& row) {
  struct Message {  // freed on every way out
    lo_message m = lo_message_new();
    ~Message() {
      if (m) lo_message_free(m);
    }
    lo_message get() const { return m; }
  } message;
  if (!message.get()) throw std::bad_alloc();
  lo_message_add_int32(message.get(), static_cast<std::int32_t>(row.frame));
  lo_message_add_float(message.get(), static_cast<float>(row.time));
  lo_message_add_int32(message.get(), static_cast<std::int32_t>(row.visible_markers));
  for (Eigen::Index c = 0; c < row.values.size(); ++c)
    lo_message_add_float(message.get(), static_cast<float>(row.values(c)));
  std::size_t size = lo_message_length(message.get(), kOscPoseAddress);
  std::vector<char> bytes(size);
  lo_message_serialise(message.get(), kOscPoseAddress, bytes.data(), &size);
  bytes.resize(size);
  return bytes;
}

}  // namespace s2kf::cli
