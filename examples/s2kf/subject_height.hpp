/// @file
/// The subject's body height for `s2kf track` and `s2kf calibrate`: given, from the marker-set file,
/// or estimated from rigid marker pairs in the recording.
#pragma once

#include "command.hpp"
#include "marker_set_json.hpp"

#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/track/height_estimate.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

namespace s2kf::cli {

struct SubjectHeight {
  double mm = 0;
  std::string source;  ///< "given", "from the marker-set file", "estimated from N rigid marker pairs"
};

/// `given_mm` when positive, else the marker-set file's height, else the estimate from up to 200
/// frames spread through the recording (the reader is left at frame 0); nullopt when the markers
/// allow no estimate. A height no person has (outside 300-3000 mm) is a UserError naming `input`.
inline std::optional<SubjectHeight> subject_height(c3d::C3dReader& reader, const MarkerSetChoice& choice,
                                                   double given_mm, const std::string& input) {
  SubjectHeight height{given_mm, "given"};
  if (height.mm <= 0 && choice.set.height_mm) height = {*choice.set.height_mm, "from the marker-set file"};
  if (height.mm <= 0) {
    track::HeightEstimator estimator(choice.model, choice.mapping);
    c3d::Frame frame;
    const std::int64_t frames = reader.info().frame_count;
    const std::int64_t step = std::max<std::int64_t>(1, frames / 200);
    for (std::int64_t f = 0; f < frames; f += step) {
      reader.seek_frame(f);
      if (!reader.read_frame(frame)) break;
      estimator.add_frame(frame.positions, frame.visible);
    }
    reader.seek_frame(0);
    const std::optional<double> estimate = estimator.height_mm();
    if (!estimate) return std::nullopt;
    height = {*estimate, "estimated from " + std::to_string(estimator.pair_count()) + " rigid marker pairs"};
  }
  if (!(height.mm > 300 && height.mm < 3000))
    throw UserError(input + ": a body height of " +
                    std::to_string(static_cast<long>(std::lround(height.mm))) +
                    " mm is not a person's; check the file's units or give --height");
  return height;
}

}  // namespace s2kf::cli
