// libFuzzer target for the C3D reader: any input must give a C3dError or a consistent result,
// never a crash, an endless loop or an unbounded allocation (ASan and UBSan watch).
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>

#include "s2kf/io/c3d_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    s2kf::c3d::C3dReader reader(
        std::make_unique<std::istringstream>(std::string(reinterpret_cast<const char*>(data), size)),
        "fuzz.c3d");
    const auto& info = reader.info();
    if (info.data_offset + info.frame_count * info.frame_bytes > static_cast<std::int64_t>(size))
      std::abort();
    s2kf::MarkerFrame frame;
    for (int f = 0; f < 256 && reader.read_frame(frame); ++f)
      for (Eigen::Index p = 0; p < frame.positions.cols(); ++p)
        if (frame.visible(p) != frame.positions.col(p).allFinite()) std::abort();
  } catch (const s2kf::c3d::C3dError&) {
  }
  return 0;
}
